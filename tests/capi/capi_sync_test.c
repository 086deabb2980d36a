/* The synchronous C API from C99: intrinsics, process_frame (U16 and F32 depth, RGB/BGR colour,
 * strides), camera poses against the synthetic room's ground truth, objects, stats, meshes
 * (extract + atomic PLY), renders against the input depth, and every error path.
 * Usage: capi_sync_test <folder written by capi_test_frames>.
 * Prints "capi_sync_test: N checks passed" or FAILED lines. */
#include <emf/emf.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Absolute camera position error after 11 frames without alignment (as the C++ SLAM test). */
#define POSE_TOLERANCE_M 0.03
/* Rotation error of the camera, degrees. */
#define ROTATION_TOLERANCE_DEG 2.0
/* Median |rendered - measured| depth at the last camera, metres (about a voxel). */
#define RENDER_TOLERANCE_M 0.02
/* Normals of extracted meshes are unit length to float precision. */
#define NORMAL_TOLERANCE 1e-3
#define MAX_FRAMES 64

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

typedef struct frames {
  int width, height, count;
  double fx, fy, cx, cy;
  double timestamp[MAX_FRAMES];
  double gt[MAX_FRAMES][12];
} frames;

static void* readFile(const char* dir, const char* pattern, int index, size_t bytes) {
  char path[4096];
  FILE* f;
  void* data = malloc(bytes);
  snprintf(path, sizeof(path), pattern, dir, index);
  f = fopen(path, "rb");
  if (!f || !data || fread(data, 1, bytes, f) != bytes) {
    printf("FAILED: cannot read %s\n", path);
    exit(1);
  }
  fclose(f);
  return data;
}

static void readList(const char* dir, frames* fr) {
  char path[4096];
  FILE* f;
  int i, j;
  snprintf(path, sizeof(path), "%s/frames.txt", dir);
  f = fopen(path, "r");
  if (!f ||
      fscanf(f, "%d %d %lf %lf %lf %lf %d", &fr->width, &fr->height, &fr->fx, &fr->fy, &fr->cx,
             &fr->cy, &fr->count) != 7 ||
      fr->count > MAX_FRAMES) {
    printf("FAILED: cannot read %s\n", path);
    exit(1);
  }
  for (i = 0; i < fr->count; ++i) {
    if (fscanf(f, "%lf", &fr->timestamp[i]) != 1) exit(1);
    for (j = 0; j < 12; ++j) {
      if (fscanf(f, "%lf", &fr->gt[i][j]) != 1) exit(1);
    }
  }
  fclose(f);
}

/* Rotation angle between the rotation parts of two row-major 3x4 poses, degrees. */
static double rotationErrorDeg(const double* a, const double* b) {
  double trace = 0;
  int i, k;
  for (i = 0; i < 3; ++i) {
    for (k = 0; k < 3; ++k) trace += a[4 * k + i] * b[4 * k + i]; /* trace(A^T B) */
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

static int compareFloat(const void* a, const void* b) {
  const float x = *(const float*)a, y = *(const float*)b;
  return x < y ? -1 : x > y ? 1 : 0;
}

static emf_system* createSystem(void) {
  emf_system_options opts;
  emf_system* sys = NULL;
  emf_system_options_init(&opts);
  /* As the C++ SLAM test: a 5.12 m background volume at 2 cm. */
  opts.config_yaml = "map: {memory_mb: 64, background_voxel_m: 0.02, background_resolution: 256}\n";
  CHECK(emf_system_create(&opts, &sys) == EMF_OK);
  return sys;
}

int main(int argc, char** argv) {
  frames fr;
  emf_system* sys;
  emf_intrinsics k;
  emf_frame frame;
  emf_frame_result result;
  emf_stats stats;
  emf_object_info objects[4];
  emf_mesh* mesh = NULL;
  int32_t count = -1;
  uint16_t* depth16 = NULL;
  unsigned char* rgb = NULL;
  float* depth_f = NULL;
  float* last_depth = NULL;
  unsigned char* padded = NULL;
  float* render_depth;
  int32_t* render_ids;
  float* diffs;
  size_t pixels, i;
  int n, j, valid, background;
  double max_t_err = 0, max_r_err = 0;
  char ply[4096], line[256];
  FILE* f;
  long ply_vertices = -1, ply_faces = -1;

  if (argc != 2) {
    printf("usage: capi_sync_test <frames folder>\n");
    return 2;
  }
  readList(argv[1], &fr);
  pixels = (size_t)fr.width * (size_t)fr.height;

  sys = createSystem();
  if (!sys) return 1;

  /* ---- before set_intrinsics ---- */
  emf_frame_init(&frame);
  CHECK(frame.struct_size == sizeof(emf_frame));
  CHECK(frame.depth.struct_size == sizeof(emf_image));
  depth16 = (uint16_t*)readFile(argv[1], "%s/depth-%d.u16", 0, pixels * 2);
  frame.depth.format = EMF_PIXEL_DEPTH_U16;
  frame.depth.width = fr.width;
  frame.depth.height = fr.height;
  frame.depth.data = depth16;
  frame.depth_scale = 5000.0;
  frame.timestamp = fr.timestamp[0];
  CHECK_MSG(emf_system_process_frame(sys, &frame, NULL), EMF_ERROR_STATE,
            "emf_system_set_intrinsics");
  CHECK_MSG(emf_system_render(sys, NULL, NULL, NULL), EMF_ERROR_STATE, "emf_system_set_intrinsics");
  CHECK_MSG(emf_system_extract_mesh(sys, 0, &mesh), EMF_ERROR_STATE, "set_intrinsics");
  CHECK(mesh == NULL);
  CHECK(emf_system_get_objects(sys, NULL, 0, &count) == EMF_OK);
  CHECK(count == 0);
  memset(&stats, 0, sizeof(stats));
  stats.struct_size = sizeof(stats);
  CHECK(emf_system_get_stats(sys, &stats) == EMF_OK);
  CHECK(stats.frames_processed == 0 && stats.pool_blocks_total == 0);

  /* ---- set_intrinsics errors ---- */
  k.fx = fr.fx;
  k.fy = fr.fy;
  k.cx = fr.cx;
  k.cy = fr.cy;
  k.width = fr.width;
  k.height = fr.height;
  CHECK_MSG(emf_system_set_intrinsics(NULL, &k), EMF_ERROR_INVALID_ARGUMENT, "system is NULL");
  CHECK_MSG(emf_system_set_intrinsics(sys, NULL), EMF_ERROR_INVALID_ARGUMENT, "intrinsics is NULL");
  k.fx = 0;
  CHECK_MSG(emf_system_set_intrinsics(sys, &k), EMF_ERROR_INVALID_ARGUMENT, "must be positive");
  k.fx = fr.fx;
  k.width = -4;
  CHECK_MSG(emf_system_set_intrinsics(sys, &k), EMF_ERROR_INVALID_ARGUMENT, "width=-4");
  k.width = fr.width;
  /* Far-off values are not a camera (the map's ray walks would be unbounded). */
  k.cx = -1e7;
  CHECK_MSG(emf_system_set_intrinsics(sys, &k), EMF_ERROR_INVALID_ARGUMENT, "principal point");
  k.cx = fr.cx;
  k.fx = 0.5;
  CHECK_MSG(emf_system_set_intrinsics(sys, &k), EMF_ERROR_INVALID_ARGUMENT, "1/20 of the image");
  k.fx = fr.fx;
  k.width = 2147483647;
  CHECK_MSG(emf_system_set_intrinsics(sys, &k), EMF_ERROR_INVALID_ARGUMENT, "image size");
  k.width = fr.width;
  CHECK(emf_system_set_intrinsics(sys, &k) == EMF_OK);
  CHECK_MSG(emf_system_set_intrinsics(sys, &k), EMF_ERROR_STATE, "already set");

  /* ---- process_frame argument errors (nothing is processed) ---- */
  memset(&result, 0, sizeof(result));
  result.struct_size = sizeof(result);
  CHECK_MSG(emf_system_process_frame(NULL, &frame, &result), EMF_ERROR_INVALID_ARGUMENT,
            "system is NULL");
  CHECK_MSG(emf_system_process_frame(sys, NULL, &result), EMF_ERROR_INVALID_ARGUMENT,
            "emf_frame is NULL");
  frame.struct_size = 8;
  CHECK_MSG(emf_system_process_frame(sys, &frame, &result), EMF_ERROR_INVALID_ARGUMENT,
            "sizeof(emf_frame)");
  frame.struct_size = sizeof(frame);
  result.struct_size = 16;
  CHECK_MSG(emf_system_process_frame(sys, &frame, &result), EMF_ERROR_INVALID_ARGUMENT,
            "sizeof(emf_frame_result)");
  result.struct_size = sizeof(result);
  frame.depth.struct_size = 3;
  CHECK_MSG(emf_system_process_frame(sys, &frame, &result), EMF_ERROR_INVALID_ARGUMENT,
            "depth.struct_size");
  frame.depth.struct_size = sizeof(emf_image);
  frame.depth.width = fr.width / 2;
  CHECK_MSG(emf_system_process_frame(sys, &frame, &result), EMF_ERROR_INVALID_ARGUMENT,
            "but the intrinsics are");
  frame.depth.width = fr.width;
  frame.depth.format = EMF_PIXEL_GRAY8;
  CHECK_MSG(emf_system_process_frame(sys, &frame, &result), EMF_ERROR_INVALID_ARGUMENT,
            "not a depth format");
  frame.depth.format = EMF_PIXEL_DEPTH_U16;
  frame.depth_scale = 0;
  CHECK_MSG(emf_system_process_frame(sys, &frame, &result), EMF_ERROR_INVALID_ARGUMENT,
            "depth_scale");
  frame.depth_scale = 5000.0;
  frame.depth.data = NULL;
  CHECK_MSG(emf_system_process_frame(sys, &frame, &result), EMF_ERROR_INVALID_ARGUMENT,
            "depth.data is NULL");
  frame.depth.data = depth16;
  frame.depth.stride_bytes = 10;
  CHECK_MSG(emf_system_process_frame(sys, &frame, &result), EMF_ERROR_INVALID_ARGUMENT,
            "stride_bytes");
  frame.depth.stride_bytes = 0;
  frame.color.format = EMF_PIXEL_GRAY8;
  frame.color.data = depth16;
  frame.color.width = fr.width;
  frame.color.height = fr.height;
  CHECK_MSG(emf_system_process_frame(sys, &frame, &result), EMF_ERROR_INVALID_ARGUMENT,
            "color.format");
  frame.color.data = NULL;
  memset(&stats, 0, sizeof(stats));
  stats.struct_size = sizeof(stats);
  CHECK(emf_system_get_stats(sys, &stats) == EMF_OK);
  CHECK(stats.frames_processed == 0);
  CHECK(stats.detector_runs == 0 && stats.detector_crashes == 0); /* no detector configured */
  /* A caller built before the detector fields were appended: accepted, and nothing written past
   * its struct_size. */
  stats.detector_runs = -7;
  stats.struct_size = offsetof(emf_stats, detector_runs);
  CHECK(emf_system_get_stats(sys, &stats) == EMF_OK);
  CHECK(stats.detector_runs == -7 && stats.struct_size == offsetof(emf_stats, detector_runs));
  free(depth16);
  depth16 = NULL;

  /* ---- the sequence: even frames U16 + RGB (tight), odd frames F32 + BGR (padded rows) ---- */
  for (n = 0; n < fr.count; ++n) {
    emf_frame_init(&frame);
    frame.timestamp = fr.timestamp[n];
    depth16 = (uint16_t*)readFile(argv[1], "%s/depth-%d.u16", n, pixels * 2);
    rgb = (unsigned char*)readFile(argv[1], "%s/color-%d.rgb", n, pixels * 3);
    frame.depth.width = frame.color.width = fr.width;
    frame.depth.height = frame.color.height = fr.height;
    free(depth_f);
    depth_f = (float*)malloc(pixels * sizeof(float));
    for (i = 0; i < pixels; ++i) depth_f[i] = depth16[i] ? (float)(depth16[i] / 5000.0) : 0.0f;
    if (n % 2 == 0) {
      frame.depth.format = EMF_PIXEL_DEPTH_U16;
      frame.depth.data = depth16;
      frame.depth_scale = 5000.0;
      frame.color.format = EMF_PIXEL_RGB8;
      frame.color.data = rgb;
    } else {
      const size_t row = (size_t)fr.width * 3, stride = row + 13;
      int y;
      frame.depth.format = EMF_PIXEL_DEPTH_F32;
      frame.depth.data = depth_f;
      free(padded);
      padded = (unsigned char*)malloc(stride * (size_t)fr.height);
      for (y = 0; y < fr.height; ++y) {
        size_t x;
        for (x = 0; x < (size_t)fr.width; ++x) { /* RGB -> BGR */
          padded[y * stride + 3 * x + 0] = rgb[y * row + 3 * x + 2];
          padded[y * stride + 3 * x + 1] = rgb[y * row + 3 * x + 1];
          padded[y * stride + 3 * x + 2] = rgb[y * row + 3 * x + 0];
        }
      }
      frame.color.format = EMF_PIXEL_BGR8;
      frame.color.stride_bytes = stride;
      frame.color.data = padded;
    }
    memset(&result, 0, sizeof(result));
    result.struct_size = sizeof(result);
    CHECK(emf_system_process_frame(sys, &frame, &result) == EMF_OK);
    CHECK(result.struct_size == sizeof(result));
    CHECK(result.frame_index == n);
    CHECK(result.timestamp == fr.timestamp[n]);
    CHECK(result.tracking_lost == 0);
    CHECK(result.object_count == 0); /* objects appear with the EM loop */
    CHECK(result.processing_ms > 0);
    CHECK(result.latency_ms == 0);
    CHECK(result.pool_blocks_used > 0);
    {
      const double te = translationError(result.T_world_camera.m, fr.gt[n]);
      const double re = rotationErrorDeg(result.T_world_camera.m, fr.gt[n]);
      if (te > max_t_err) max_t_err = te;
      if (re > max_r_err) max_r_err = re;
      CHECK(te < POSE_TOLERANCE_M);
      CHECK(re < ROTATION_TOLERANCE_DEG);
    }
    if (n == 0) {
      for (j = 0; j < 12; ++j) CHECK(result.T_world_camera.m[j] == (j % 5 == 0 ? 1.0 : 0.0));
      /* the same timestamp again is rejected and not processed */
      CHECK_MSG(emf_system_process_frame(sys, &frame, &result), EMF_ERROR_INVALID_ARGUMENT,
                "does not increase");
      /* a timestamp that is not a number says so */
      frame.timestamp = NAN;
      CHECK_MSG(emf_system_process_frame(sys, &frame, &result), EMF_ERROR_INVALID_ARGUMENT,
                "is not a finite number");
      frame.timestamp = fr.timestamp[n];
    }
    free(depth16);
    depth16 = NULL;
    free(rgb);
    rgb = NULL;
    free(last_depth);
    last_depth = depth_f;
    depth_f = NULL;
  }
  printf("max camera error: %.4f m, %.3f deg over %d frames\n", max_t_err, max_r_err, fr.count);

  /* ---- stats and objects ---- */
  memset(&stats, 0, sizeof(stats));
  stats.struct_size = sizeof(stats);
  CHECK(emf_system_get_stats(sys, &stats) == EMF_OK);
  CHECK(stats.frames_processed == fr.count);
  CHECK(stats.frames_lost == 0);
  CHECK(stats.pool_blocks_used > 0 && stats.pool_blocks_used <= stats.pool_blocks_total);
  CHECK(stats.pool_bytes == stats.pool_blocks_total * 2048);
  CHECK(stats.frames_dropped == 0 && stats.frames_produced == 0);
  stats.struct_size = 8;
  CHECK_MSG(emf_system_get_stats(sys, &stats), EMF_ERROR_INVALID_ARGUMENT, "struct_size");
  CHECK_MSG(emf_system_get_stats(NULL, &stats), EMF_ERROR_INVALID_ARGUMENT, "system is NULL");
  count = -1;
  objects[0].struct_size = sizeof(objects[0]);
  CHECK(emf_system_get_objects(sys, objects, 4, &count) == EMF_OK);
  CHECK(count == 0);
  CHECK_MSG(emf_system_get_objects(sys, objects, 4, NULL), EMF_ERROR_INVALID_ARGUMENT,
            "count is NULL");
  CHECK_MSG(emf_system_get_objects(sys, NULL, 4, &count), EMF_ERROR_INVALID_ARGUMENT, "is NULL");
  objects[0].struct_size = 4;
  CHECK_MSG(emf_system_get_objects(sys, objects, 4, &count), EMF_ERROR_INVALID_ARGUMENT,
            "(set it to sizeof(emf_object_info))");
  CHECK_MSG(emf_system_get_objects(sys, objects, -1, &count), EMF_ERROR_INVALID_ARGUMENT,
            "negative");

  /* ---- mesh of the background ---- */
  CHECK(emf_system_extract_mesh(sys, 0, &mesh) == EMF_OK);
  CHECK(mesh != NULL);
  if (mesh) {
    int bad_normals = 0, bad_indices = 0;
    CHECK(mesh->struct_size == sizeof(emf_mesh));
    CHECK(mesh->vertex_count > 1000);
    CHECK(mesh->triangle_count > 1000);
    for (j = 0; j < mesh->vertex_count; ++j) {
      const float* nrm = mesh->normals + 3 * j;
      const double len = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
      if (fabs(len - 1.0) > NORMAL_TOLERANCE) ++bad_normals;
    }
    for (j = 0; j < 3 * mesh->triangle_count; ++j) {
      if (mesh->indices[j] >= (uint32_t)mesh->vertex_count) ++bad_indices;
    }
    CHECK(bad_normals == 0);
    CHECK(bad_indices == 0);
    /* The same mesh, written atomically as binary PLY: the header counts match. */
    snprintf(ply, sizeof(ply), "%s/background.ply", argv[1]);
    CHECK(emf_system_save_mesh(sys, 0, ply) == EMF_OK);
    f = fopen(ply, "rb");
    CHECK(f != NULL);
    while (f && fgets(line, sizeof(line), f)) {
      sscanf(line, "element vertex %ld", &ply_vertices);
      sscanf(line, "element face %ld", &ply_faces);
      if (strncmp(line, "end_header", 10) == 0) break;
    }
    if (f) fclose(f);
    CHECK(ply_vertices == mesh->vertex_count);
    CHECK(ply_faces == mesh->triangle_count);
    emf_mesh_destroy(mesh);
  }
  emf_mesh_destroy(NULL); /* no-op */
  mesh = (emf_mesh*)&fr;  /* must be reset to NULL on error */
  CHECK_MSG(emf_system_extract_mesh(sys, 999, &mesh), EMF_ERROR_NOT_FOUND, "999");
  CHECK(mesh == NULL);
  CHECK_MSG(emf_system_extract_mesh(sys, 0, NULL), EMF_ERROR_INVALID_ARGUMENT, "out is NULL");
  CHECK_MSG(emf_system_save_mesh(sys, 0, NULL), EMF_ERROR_INVALID_ARGUMENT, "path");
  CHECK_MSG(emf_system_save_mesh(sys, 0, "/nonexistent-dir/x.ply"), EMF_ERROR_IO,
            "/nonexistent-dir/x.ply");
  CHECK_MSG(emf_system_save_mesh(sys, 7, ply), EMF_ERROR_NOT_FOUND, "7");

  /* ---- render at the current camera: the map reproduces the last measured depth ---- */
  render_depth = (float*)malloc(pixels * sizeof(float));
  render_ids = (int32_t*)malloc(pixels * sizeof(int32_t));
  diffs = (float*)malloc(pixels * sizeof(float));
  CHECK(emf_system_render(sys, NULL, render_depth, render_ids) == EMF_OK);
  /* The static room has no object and no detector: no E-step ran, so no association map. */
  CHECK_MSG(emf_system_get_association(sys, 0, render_depth), EMF_ERROR_NOT_FOUND,
            "no E-step ran in the last frame");
  CHECK_MSG(emf_system_get_association(sys, 0, NULL), EMF_ERROR_INVALID_ARGUMENT, "q is NULL");
  valid = 0;
  background = 0;
  for (i = 0; i < pixels; ++i) {
    if (render_ids[i] == 0) ++background;
    CHECK(render_ids[i] == 0 || render_ids[i] == -1);
    if (render_ids[i] == -1) CHECK(isnan(render_depth[i]));
    if (render_ids[i] == 0 && last_depth[i] > 0) {
      diffs[valid++] = (float)fabs(render_depth[i] - last_depth[i]);
    }
  }
  CHECK(background > (int)(pixels * 9 / 10));
  qsort(diffs, (size_t)valid, sizeof(float), compareFloat);
  CHECK(valid > 0 && diffs[valid / 2] < RENDER_TOLERANCE_M);
  printf("render: %d background pixels of %d, median |render - input| %.4f m\n", background,
         (int)pixels, valid > 0 ? diffs[valid / 2] : -1.0);
  {
    /* An explicit pose equal to the current camera renders the same depth. */
    float* again = (float*)malloc(pixels * sizeof(float));
    int differ = 0;
    CHECK(emf_system_render(sys, &result.T_world_camera, again, NULL) == EMF_OK);
    for (i = 0; i < pixels; ++i) {
      if (!(again[i] == render_depth[i] || (isnan(again[i]) && isnan(render_depth[i])))) ++differ;
    }
    CHECK(differ == 0);
    free(again);
  }
  CHECK(emf_system_render(sys, NULL, NULL, NULL) == EMF_OK);
  CHECK_MSG(emf_system_render(NULL, NULL, render_depth, NULL), EMF_ERROR_INVALID_ARGUMENT,
            "system is NULL");
  {
    /* Poses that are not rigid transforms: all zero, a scaled rotation, a NaN. */
    emf_pose bad;
    memset(&bad, 0, sizeof(bad));
    CHECK_MSG(emf_system_render(sys, &bad, render_depth, NULL), EMF_ERROR_INVALID_ARGUMENT,
              "not a rigid transform");
    bad = result.T_world_camera;
    for (i = 0; i < 12; ++i) bad.m[i] *= 2.0;
    CHECK_MSG(emf_system_render(sys, &bad, render_depth, NULL), EMF_ERROR_INVALID_ARGUMENT,
              "not a rigid transform");
    bad = result.T_world_camera;
    bad.m[3] = NAN;
    CHECK_MSG(emf_system_render(sys, &bad, render_depth, NULL), EMF_ERROR_INVALID_ARGUMENT,
              "not a rigid transform");
  }
  free(render_depth);
  free(render_ids);
  free(diffs);
  free(last_depth);
  free(padded);

  emf_system_destroy(sys);
  emf_system_destroy(NULL);

  /* A detector plugin that cannot be found: NOT_FOUND (not an internal error), naming it. */
  {
    emf_system_options opts;
    emf_system* with_plugin = NULL;
    emf_system_options_init(&opts);
    opts.config_yaml = "map: {memory_mb: 16}\ndetector: {plugin: no_such_detector}\n";
    CHECK(emf_system_create(&opts, &with_plugin) == EMF_OK);
    CHECK_MSG(emf_system_set_intrinsics(with_plugin, &k), EMF_ERROR_NOT_FOUND,
              "detector plugin 'no_such_detector' not found");
    emf_system_destroy(with_plugin);
  }
  if (g_failed == 0) printf("capi_sync_test: %d checks passed\n", g_checks);
  return g_failed == 0 ? 0 : 1;
}
