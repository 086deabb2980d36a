/* Test detector plugins in plain C, one source compiled several ways (TEST_PLUGIN_KIND):
 *  1 "malformed": one good detection plus NaN score, negative box, wrong-size mask, bad
 *     probabilities, empty class name — the host must keep only the good one.
 *  2 "badabi": reports ABI version 999.
 *  3 "failing": create fails when config is "fail", detect always fails with a message.
 *  4 "noentry": exports no entry symbol.
 *  5 "refuses": entry returns NULL for every host version.
 *  6 "newonly": sets EMF_DETECTOR_FLAG_NEW_OBJECTS_ONLY.
 *  7 "oldapi": sets the flag but reports the struct_size of a plugin built before the flags
 *     field existed: the host must not read it.
 *  8 "newer": built against a future header with two fields appended to emf_detection: the
 *     host must step through the array by the plugin's struct_size. Two good detections, and a
 *     third whose struct_size differs from the first's.
 *  9 "faulty": one good detection per frame, except on the frames its config names:
 *     "segfault=N,abort=M,hang=K,garbage=G" (any subset; -1 = never) — SIGSEGV, abort(),
 *     sleeping forever, and a result whose detections pointer is garbage (the host's reading of
 *     it crashes). For process isolation (detector.isolation: process). */
#include <emf/emf_detector.h>
#include <math.h>
#include <signal.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#if TEST_PLUGIN_KIND == 4
EMF_DETECTOR_EXPORT int not_the_entry(void);
EMF_DETECTOR_EXPORT int not_the_entry(void) { return 42; }
#else

/* emf_detection as a future header might have it. */
typedef struct newer_detection {
  emf_detection base;
  int32_t track_id;
  double extra;
} newer_detection;

struct emf_detector {
  int width, height;
  long segfault_at, abort_at, hang_at, garbage_at; /* "faulty": frame indices, -1 = never */
  uint8_t* full_mask;
  uint8_t* small_mask;
  float* bad_probability;
  emf_detection dets[6];
  newer_detection newer[3];
  emf_detection_result result;
};

static emf_status create(const emf_detector_create_info* info, emf_detector** out, char* error,
                         size_t error_size) {
  emf_detector* d;
  if (TEST_PLUGIN_KIND == 3 && info->config && strcmp(info->config, "fail") == 0) {
    snprintf(error, error_size, "test plugin: asked to fail");
    return EMF_ERROR_CONFIG;
  }
  d = (emf_detector*)calloc(1, sizeof(emf_detector));
  d->segfault_at = d->abort_at = d->hang_at = d->garbage_at = -1;
  if (TEST_PLUGIN_KIND == 9 && info->config) {
    const char* p = info->config;
    while (*p) {
      long* field = NULL;
      if (strncmp(p, "segfault=", 9) == 0)
        field = &d->segfault_at, p += 9;
      else if (strncmp(p, "abort=", 6) == 0)
        field = &d->abort_at, p += 6;
      else if (strncmp(p, "hang=", 5) == 0)
        field = &d->hang_at, p += 5;
      else if (strncmp(p, "garbage=", 8) == 0)
        field = &d->garbage_at, p += 8;
      if (!field) {
        snprintf(error, error_size, "test plugin: unknown config '%s'", p);
        free(d);
        return EMF_ERROR_CONFIG;
      }
      *field = strtol(p, (char**)&p, 10);
      if (*p == ',') ++p;
    }
  }
  d->width = info->intrinsics.width;
  d->height = info->intrinsics.height;
  *out = d;
  return EMF_OK;
}

static emf_detection makeDetection(const char* name, float score, int x, int y, int w, int h,
                                   int mw, int mh, const uint8_t* mask, const float* prob) {
  emf_detection e;
  memset(&e, 0, sizeof(e));
  e.struct_size = sizeof(e);
  e.class_name = name;
  e.score = score;
  e.box_x = x;
  e.box_y = y;
  e.box_width = w;
  e.box_height = h;
  e.mask_width = mw;
  e.mask_height = mh;
  e.mask = mask;
  e.mask_probability = prob;
  return e;
}

static emf_status detect(emf_detector* d, const emf_detector_frame* f, emf_detection_result** out,
                         char* error, size_t error_size) {
  int x, y, w = f->depth.width, h = f->depth.height;
  size_t n = (size_t)w * (size_t)h;
  *out = NULL;
  if (TEST_PLUGIN_KIND == 3) {
    snprintf(error, error_size, "test plugin: detect always fails");
    return EMF_ERROR_INTERNAL;
  }
  free(d->full_mask);
  free(d->small_mask);
  free(d->bad_probability);
  d->full_mask = (uint8_t*)calloc(n, 1);
  d->small_mask = (uint8_t*)calloc(4, 1);
  d->bad_probability = (float*)calloc(n, sizeof(float));
  for (y = 10; y < 30; ++y)
    for (x = 20; x < 60; ++x) d->full_mask[(size_t)y * w + x] = 1;
  d->bad_probability[5] = NAN;
  d->dets[0] = makeDetection("cup", 0.9f, 20, 10, 40, 20, w, h, d->full_mask, NULL);
  d->dets[1] = makeDetection("cup", NAN, 20, 10, 40, 20, w, h, d->full_mask, NULL);
  d->dets[2] = makeDetection("cup", 0.5f, -3, 10, 40, 20, w, h, d->full_mask, NULL);
  d->dets[3] = makeDetection("cup", 0.5f, 20, 10, 40, 20, 2, 2, d->small_mask, NULL);
  d->dets[4] = makeDetection("cup", 0.5f, 20, 10, 40, 20, w, h, NULL, d->bad_probability);
  d->dets[5] = makeDetection("", 0.5f, 20, 10, 40, 20, w, h, d->full_mask, NULL);
  d->result.struct_size = sizeof(d->result);
  d->result.count = 6;
  d->result.detections = d->dets;
  if (TEST_PLUGIN_KIND == 9) {
    /* raise(): a null write would be caught by UBSan first in the sanitizer builds. */
    if (f->frame_index == d->segfault_at) raise(SIGSEGV);
    if (f->frame_index == d->abort_at) abort();
    if (f->frame_index == d->hang_at) {
      for (;;) sleep(1);
    }
    d->result.count = 1;
    if (f->frame_index == d->garbage_at) {
      d->result.count = 3;
      d->result.detections = (emf_detection*)(uintptr_t)0x10;
      *out = &d->result;
      return EMF_OK;
    }
  }
  if (TEST_PLUGIN_KIND == 8) {
    for (x = 0; x < 3; ++x) {
      d->newer[x].base = makeDetection(x == 0 ? "cup" : "car", x == 0 ? 0.9f : 0.7f, 20 + 10 * x,
                                       10, 30, 20, w, h, d->full_mask, NULL);
      d->newer[x].base.struct_size = x < 2 ? sizeof(newer_detection) : sizeof(emf_detection);
      d->newer[x].track_id = 7;
      d->newer[x].extra = -1.0;
    }
    d->result.count = 3;
    d->result.detections = &d->newer[0].base;
  }
  *out = &d->result;
  return EMF_OK;
}

static void release(emf_detector* d, emf_detection_result* r) {
  (void)d;
  (void)r;
}

static void destroy(emf_detector* d) {
  if (!d) return;
  free(d->full_mask);
  free(d->small_mask);
  free(d->bad_probability);
  free(d);
}

static const emf_detector_api kApi = {
    TEST_PLUGIN_KIND == 7 ? offsetof(emf_detector_api, flags) : sizeof(emf_detector_api),
    TEST_PLUGIN_KIND == 2 ? 999u : EMF_DETECTOR_ABI_VERSION,
    "test",
    "test plugin",
    create,
    detect,
    release,
    destroy,
    TEST_PLUGIN_KIND == 6 || TEST_PLUGIN_KIND == 7 ? EMF_DETECTOR_FLAG_NEW_OBJECTS_ONLY : 0u};

EMF_DETECTOR_EXPORT const emf_detector_api* emf_detector_entry(uint32_t host_abi_version);
EMF_DETECTOR_EXPORT const emf_detector_api* emf_detector_entry(uint32_t host_abi_version) {
  (void)host_abi_version;
  return TEST_PLUGIN_KIND == 5 ? NULL : &kApi;
}
#endif
