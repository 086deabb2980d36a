/* The runtime C API from C99: a TUM folder (written by `emf synth`) through capture thread ->
 * ring -> SLAM thread; results by callback and by polling, camera poses against the folder's
 * groundtruth.txt, end of stream, stats, the runtime's system after the end, start/stop rules
 * and every error path. Usage: capi_runtime_test <TUM folder>.
 * Prints "capi_runtime_test: N checks passed" or FAILED lines. */
#include <emf/emf.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Absolute camera position error without alignment over the short sequence. */
#define POSE_TOLERANCE_M 0.03
#define ROTATION_TOLERANCE_DEG 2.0
/* Timestamps are written with 6 decimals. */
#define TIMESTAMP_TOLERANCE_S 1e-5
#define MAX_FRAMES 256
#define CONFIG "map: {memory_mb: 64, background_voxel_m: 0.02, background_resolution: 256}\n"

static int g_checks = 0;
static int g_failed = 0;

#define CHECK(cond)                                                            \
  do {                                                                         \
    ++g_checks;                                                                \
    if (!(cond)) {                                                             \
      ++g_failed;                                                              \
      printf("FAILED %s:%d: %s (last error: %s)\n", __FILE__, __LINE__, #cond, \
             emf_last_error_message());                                        \
    }                                                                          \
  } while (0)

#define CHECK_MSG(status, expected, text)                    \
  do {                                                       \
    emf_status s_ = (status);                                \
    CHECK(s_ == (expected));                                 \
    CHECK(strstr(emf_last_error_message(), (text)) != NULL); \
  } while (0)

typedef struct truth {
  int count;
  double t[MAX_FRAMES];
  double pose[MAX_FRAMES][12]; /* T_first_camera, row-major 3x4 */
} truth;

/* What the callback saw (written on the SLAM thread, read after the stream ended). */
typedef struct seen {
  int calls;
  int64_t frame_index[MAX_FRAMES];
  emf_pose pose[MAX_FRAMES];
  int objects_null_ok;
} seen;

static void onResult(const emf_frame_result* result, const emf_object_info* objects,
                     int32_t object_count, void* user_data) {
  seen* s = (seen*)user_data;
  if (s->calls < MAX_FRAMES) {
    s->frame_index[s->calls] = result->frame_index;
    s->pose[s->calls] = result->T_world_camera;
  }
  if ((object_count == 0) != (objects == NULL)) s->objects_null_ok = 0;
  ++s->calls;
}

static void quatToPose(double tx, double ty, double tz, double qx, double qy, double qz, double qw,
                       double* m) {
  m[0] = 1 - 2 * (qy * qy + qz * qz);
  m[1] = 2 * (qx * qy - qz * qw);
  m[2] = 2 * (qx * qz + qy * qw);
  m[3] = tx;
  m[4] = 2 * (qx * qy + qz * qw);
  m[5] = 1 - 2 * (qx * qx + qz * qz);
  m[6] = 2 * (qy * qz - qx * qw);
  m[7] = ty;
  m[8] = 2 * (qx * qz - qy * qw);
  m[9] = 2 * (qy * qz + qx * qw);
  m[10] = 1 - 2 * (qx * qx + qy * qy);
  m[11] = tz;
}

/* out = a^-1 * b for rigid 3x4 poses. */
static void relative(const double* a, const double* b, double* out) {
  int r, c, k;
  for (r = 0; r < 3; ++r) {
    for (c = 0; c < 4; ++c) {
      double v = 0;
      for (k = 0; k < 3; ++k) {
        v += a[4 * k + r] * (c < 3 ? b[4 * k + c] : b[4 * k + 3] - a[4 * k + 3]);
      }
      out[4 * r + c] = v;
    }
  }
}

static void readTruth(const char* dir, truth* gt) {
  char path[4096], line[512];
  double first[12], abs_pose[12];
  FILE* f;
  snprintf(path, sizeof(path), "%s/groundtruth.txt", dir);
  f = fopen(path, "r");
  if (!f) {
    printf("FAILED: cannot read %s\n", path);
    exit(1);
  }
  gt->count = 0;
  while (fgets(line, sizeof(line), f) && gt->count < MAX_FRAMES) {
    double t, tx, ty, tz, qx, qy, qz, qw;
    if (line[0] == '#') continue;
    if (sscanf(line, "%lf %lf %lf %lf %lf %lf %lf %lf", &t, &tx, &ty, &tz, &qx, &qy, &qz, &qw) != 8)
      continue;
    quatToPose(tx, ty, tz, qx, qy, qz, qw, abs_pose);
    if (gt->count == 0) memcpy(first, abs_pose, sizeof(first));
    gt->t[gt->count] = t;
    relative(first, abs_pose, gt->pose[gt->count]);
    ++gt->count;
  }
  fclose(f);
}

static int truthIndex(const truth* gt, double t) {
  int i;
  for (i = 0; i < gt->count; ++i) {
    if (fabs(gt->t[i] - t) < TIMESTAMP_TOLERANCE_S) return i;
  }
  return -1;
}

static double rotationErrorDeg(const double* a, const double* b) {
  double trace = 0;
  int i, k;
  for (i = 0; i < 3; ++i) {
    for (k = 0; k < 3; ++k) trace += a[4 * k + i] * b[4 * k + i];
  }
  trace = (trace - 1.0) / 2.0;
  if (trace > 1.0) trace = 1.0;
  if (trace < -1.0) trace = -1.0;
  return acos(trace) * 180.0 / 3.14159265358979323846;
}

static double translationError(const double* a, const double* b) {
  const double dx = a[3] - b[3], dy = a[7] - b[7], dz = a[11] - b[11];
  return sqrt(dx * dx + dy * dy + dz * dz);
}

static void errorPaths(const char* uri) {
  emf_runtime_options opts;
  emf_runtime* rt = (emf_runtime*)&opts;
  emf_stats stats;
  emf_frame_result result;

  CHECK_MSG(emf_runtime_create(NULL, &rt), EMF_ERROR_INVALID_ARGUMENT,
            "emf_runtime_options is NULL");
  CHECK(rt == NULL);
  emf_runtime_options_init(&opts);
  CHECK(opts.struct_size == sizeof(opts) && opts.api_version == EMF_API_VERSION);
  opts.source_uri = uri;
  CHECK_MSG(emf_runtime_create(&opts, NULL), EMF_ERROR_INVALID_ARGUMENT, "out is NULL");
  opts.struct_size = 8;
  CHECK_MSG(emf_runtime_create(&opts, &rt), EMF_ERROR_INVALID_ARGUMENT,
            "sizeof(emf_runtime_options)");
  opts.struct_size = sizeof(opts);
  opts.api_version = (EMF_VERSION_MAJOR + 1) * 10000;
  CHECK(emf_runtime_create(&opts, &rt) == EMF_ERROR_VERSION_MISMATCH);
  opts.api_version = EMF_API_VERSION;
  opts.config_yaml = "runtime: {ring_polcy: block}\n";
  CHECK_MSG(emf_runtime_create(&opts, &rt), EMF_ERROR_CONFIG, "runtime.ring_policy");
  opts.config_yaml = "runtime: {ring_policy: newest}\n";
  CHECK_MSG(emf_runtime_create(&opts, &rt), EMF_ERROR_CONFIG, "ring_policy");
  opts.config_yaml = NULL;
  opts.source_uri = "nosuch:thing";
  CHECK_MSG(emf_runtime_create(&opts, &rt), EMF_ERROR_IO, "unknown scheme");
  opts.source_uri = "tum:/nonexistent/emf-folder";
  CHECK_MSG(emf_runtime_create(&opts, &rt), EMF_ERROR_IO, "/nonexistent/emf-folder");
  CHECK(rt == NULL);

  CHECK(emf_runtime_start(NULL) == EMF_ERROR_INVALID_ARGUMENT);
  CHECK(emf_runtime_stop(NULL) == EMF_ERROR_INVALID_ARGUMENT);
  CHECK(emf_runtime_poll(NULL, 0, NULL, NULL, 0, NULL) == EMF_ERROR_INVALID_ARGUMENT);
  memset(&stats, 0, sizeof(stats));
  stats.struct_size = sizeof(stats);
  CHECK(emf_runtime_get_stats(NULL, &stats) == EMF_ERROR_INVALID_ARGUMENT);
  CHECK(emf_runtime_system(NULL) == NULL);
  emf_runtime_destroy(NULL); /* no-op */

  /* A runtime that is never started: polls are a state error (nothing would ever arrive),
   * stats are zero, destroy joins nothing. */
  emf_runtime_options_init(&opts);
  opts.source_uri = uri;
  opts.config_yaml = CONFIG;
  CHECK(emf_runtime_create(&opts, &rt) == EMF_OK);
  memset(&result, 0, sizeof(result));
  result.struct_size = sizeof(result);
  CHECK_MSG(emf_runtime_poll(rt, 100, &result, NULL, 0, NULL), EMF_ERROR_STATE, "before start");
  CHECK_MSG(emf_runtime_poll(rt, -1, &result, NULL, 0, NULL), EMF_ERROR_INVALID_ARGUMENT,
            "negative");
  result.struct_size = 4;
  CHECK_MSG(emf_runtime_poll(rt, 0, &result, NULL, 0, NULL), EMF_ERROR_INVALID_ARGUMENT,
            "sizeof(emf_frame_result)");
  CHECK_MSG(emf_runtime_poll(rt, 0, NULL, NULL, 3, NULL), EMF_ERROR_INVALID_ARGUMENT,
            "objects is NULL");
  stats.struct_size = 2;
  CHECK_MSG(emf_runtime_get_stats(rt, &stats), EMF_ERROR_INVALID_ARGUMENT, "sizeof(emf_stats)");
  stats.struct_size = sizeof(stats);
  CHECK(emf_runtime_get_stats(rt, &stats) == EMF_OK);
  CHECK(stats.frames_processed == 0 && stats.frames_produced == 0);
  /* stop before start: not restartable */
  CHECK(emf_runtime_stop(rt) == EMF_OK);
  CHECK_MSG(emf_runtime_start(rt), EMF_ERROR_STATE, "cannot be restarted");
  CHECK_MSG(emf_runtime_poll(rt, 0, NULL, NULL, 0, NULL), EMF_ERROR_STATE, "stopped");
  emf_runtime_destroy(rt);
}

int main(int argc, char** argv) {
  truth gt;
  seen cb;
  char uri[4200];
  emf_runtime_options opts;
  emf_runtime* rt = NULL;
  emf_system* sys;
  emf_frame_result result;
  emf_object_info objects[8];
  emf_stats stats;
  emf_mesh* mesh = NULL;
  emf_status s;
  int32_t count;
  int polled = 0, i, in_order = 1;
  double max_t_err = 0, max_r_err = 0;

  if (argc != 2) {
    printf("usage: capi_runtime_test <TUM folder>\n");
    return 2;
  }
  readTruth(argv[1], &gt);
  CHECK(gt.count > 5);
  snprintf(uri, sizeof(uri), "tum:%s", argv[1]);
  errorPaths(uri);

  /* ---- the whole folder through the runtime (block policy: lossless) ---- */
  memset(&cb, 0, sizeof(cb));
  cb.objects_null_ok = 1;
  emf_runtime_options_init(&opts);
  opts.source_uri = uri;
  opts.config_yaml = CONFIG "runtime: {ring_policy: block, ring_slots: 2, result_queue: 256}\n";
  opts.callback = onResult;
  opts.user_data = &cb;
  CHECK(emf_runtime_create(&opts, &rt) == EMF_OK);
  if (!rt) return 1;
  sys = emf_runtime_system(rt);
  CHECK(sys != NULL);
  CHECK(emf_runtime_start(rt) == EMF_OK);
  CHECK(emf_runtime_start(rt) == EMF_OK); /* idempotent */
  /* The runtime's system: frames only come from the source; other calls wait for the end. */
  {
    emf_frame frame;
    emf_intrinsics k = {100, 100, 50, 50, 100, 100};
    emf_frame_init(&frame);
    CHECK_MSG(emf_system_process_frame(sys, &frame, NULL), EMF_ERROR_STATE, "belongs to a runtime");
    CHECK_MSG(emf_system_set_intrinsics(sys, &k), EMF_ERROR_STATE, "belongs to a runtime");
    emf_system_destroy(sys); /* no-op: owned by the runtime */
  }
  memset(&result, 0, sizeof(result));
  result.struct_size = sizeof(result);
  objects[0].struct_size = sizeof(objects[0]);
  for (;;) {
    count = -1;
    s = emf_runtime_poll(rt, 1000, &result, objects, 8, &count);
    if (s == EMF_ERROR_TIMEOUT) continue;
    if (s != EMF_OK) break;
    {
      const int k = truthIndex(&gt, result.timestamp);
      CHECK(k == polled); /* lossless and in order */
      if (result.frame_index != polled) in_order = 0;
      CHECK(result.source_index == polled);
      CHECK(result.tracking_lost == 0);
      CHECK(count == 0 && result.object_count == 0); /* objects appear with the EM loop */
      CHECK(result.processing_ms > 0);
      CHECK(result.latency_ms >= result.processing_ms);
      CHECK(result.frames_dropped == 0);
      CHECK(result.pool_blocks_used > 0);
      if (k >= 0) {
        const double te = translationError(result.T_world_camera.m, gt.pose[k]);
        const double re = rotationErrorDeg(result.T_world_camera.m, gt.pose[k]);
        if (te > max_t_err) max_t_err = te;
        if (re > max_r_err) max_r_err = re;
        CHECK(te < POSE_TOLERANCE_M);
        CHECK(re < ROTATION_TOLERANCE_DEG);
      }
      if (polled < MAX_FRAMES && polled < cb.calls) {
        CHECK(memcmp(&cb.pose[polled], &result.T_world_camera, sizeof(emf_pose)) == 0);
      }
    }
    ++polled;
  }
  CHECK_MSG(s, EMF_ERROR_END_OF_STREAM, "end of stream");
  CHECK(in_order);
  CHECK(polled == gt.count);
  printf("runtime: %d results, max camera error %.4f m, %.3f deg\n", polled, max_t_err, max_r_err);
  CHECK(emf_runtime_poll(rt, 0, &result, NULL, 0, NULL) == EMF_ERROR_END_OF_STREAM);
  CHECK(emf_runtime_start(rt) == EMF_OK); /* no-op after the end */

  memset(&stats, 0, sizeof(stats));
  stats.struct_size = sizeof(stats);
  CHECK(emf_runtime_get_stats(rt, &stats) == EMF_OK);
  CHECK(stats.frames_processed == gt.count);
  CHECK(stats.frames_produced == gt.count);
  CHECK(stats.frames_dropped == 0);
  CHECK(stats.results_dropped == 0);
  CHECK(stats.frames_lost == 0);
  CHECK(stats.pool_blocks_used > 0 && stats.pool_bytes > 0);

  /* The callback saw every frame, in order, before its poll. */
  CHECK(cb.calls == gt.count);
  for (i = 0; i < cb.calls && i < MAX_FRAMES; ++i) CHECK(cb.frame_index[i] == i);
  CHECK(cb.objects_null_ok);

  /* ---- the runtime's system after the end: stats, objects, mesh, render ---- */
  {
    emf_stats ss;
    memset(&ss, 0, sizeof(ss));
    ss.struct_size = sizeof(ss);
    CHECK(emf_system_get_stats(sys, &ss) == EMF_OK);
    CHECK(ss.frames_processed == gt.count);
    CHECK(ss.pool_blocks_used == stats.pool_blocks_used);
    count = -1;
    CHECK(emf_system_get_objects(sys, NULL, 0, &count) == EMF_OK);
    CHECK(count == 0);
    CHECK(emf_system_extract_mesh(sys, 0, &mesh) == EMF_OK);
    CHECK(mesh != NULL && mesh->vertex_count > 1000);
    emf_mesh_destroy(mesh);
    CHECK(emf_system_render(sys, NULL, NULL, NULL) == EMF_OK);
  }

  CHECK(emf_runtime_stop(rt) == EMF_OK);
  CHECK(emf_runtime_stop(rt) == EMF_OK); /* idempotent */
  /* Ended stays ended. */
  CHECK(emf_runtime_poll(rt, 0, NULL, NULL, 0, NULL) == EMF_ERROR_END_OF_STREAM);
  emf_runtime_destroy(rt);

  /* ---- drop_oldest on a recorded source: the counts add up ---- */
  emf_runtime_options_init(&opts);
  opts.source_uri = uri;
  opts.config_yaml = CONFIG "runtime: {ring_policy: drop_oldest, ring_slots: 2, result_queue: 2}\n";
  CHECK(emf_runtime_create(&opts, &rt) == EMF_OK);
  if (!rt) return 1;
  CHECK(emf_runtime_start(rt) == EMF_OK);
  do {
    s = emf_runtime_poll(rt, 1000, NULL, NULL, 0, NULL);
  } while (s == EMF_OK || s == EMF_ERROR_TIMEOUT);
  CHECK(s == EMF_ERROR_END_OF_STREAM);
  memset(&stats, 0, sizeof(stats));
  stats.struct_size = sizeof(stats);
  CHECK(emf_runtime_get_stats(rt, &stats) == EMF_OK);
  CHECK(stats.frames_produced == gt.count);
  CHECK(stats.frames_processed + stats.frames_dropped == stats.frames_produced);
  printf("drop_oldest: produced %lld, processed %lld, dropped %lld\n",
         (long long)stats.frames_produced, (long long)stats.frames_processed,
         (long long)stats.frames_dropped);
  emf_runtime_destroy(rt); /* without stop: destroy stops */

  if (g_failed == 0) printf("capi_runtime_test: %d checks passed\n", g_checks);
  return g_failed == 0 ? 0 : 1;
}
