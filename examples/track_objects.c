/* track_objects: runs an RGB-D source through the emf runtime and prints, per frame, the camera
 * pose and the pose of every object. Plain C99; includes only <emf/emf.h>.
 *
 *   track_objects <source-uri> [config-yaml]
 *
 *   source-uri   tum:<folder>, synth:room?frames=30, openni2:, v4l2:/dev/video0, ...
 *   config-yaml  YAML applied on top of the defaults, e.g.
 *                "runtime: {ring_policy: drop_oldest}" for a live sensor
 *
 * Output (one line per item, numbers in metres; poses are row-major 3x4 [R | t]):
 *   frame <index> source=<source index> t=<timestamp s> lost=<0|1> latency_ms=<ms>
 *         T_world_camera= r00 r01 r02 tx r10 r11 r12 ty r20 r21 r22 tz
 *   object <id> class=<name> state=<state> T_world_object= <12 numbers>
 *   end frames=<processed> produced=<n> dropped=<n> status=<EMF_...>
 * Ctrl-C stops the runtime cleanly. Exit code 0 at the end of a recorded source, 1 on error. */
#include <emf/emf.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>

#define MAX_OBJECTS 64

static volatile sig_atomic_t g_interrupted = 0;

static void onSignal(int sig) {
  (void)sig;
  g_interrupted = 1;
}

/* Called on emf's SLAM thread: only counts (printing happens on the main thread). */
static void onResult(const emf_frame_result* result, const emf_object_info* objects,
                     int32_t object_count, void* user_data) {
  long* frames_seen = (long*)user_data;
  (void)result;
  (void)objects;
  (void)object_count;
  ++*frames_seen;
}

static const char* stateName(emf_object_state state) {
  switch (state) {
    case EMF_OBJECT_TRACKED:
      return "tracked";
    case EMF_OBJECT_INVISIBLE:
      return "invisible";
    case EMF_OBJECT_DELETED:
      return "deleted";
    case EMF_OBJECT_LOST:
      return "lost";
    case EMF_OBJECT_DORMANT:
      return "dormant";
  }
  return "unknown";
}

static void printPose(const emf_pose* pose) {
  int i;
  for (i = 0; i < 12; ++i) printf(" %.6f", pose->m[i]);
}

int main(int argc, char** argv) {
  emf_runtime_options options;
  emf_runtime* runtime = NULL;
  emf_frame_result result;
  emf_object_info objects[MAX_OBJECTS];
  emf_stats stats;
  emf_status status;
  long frames_seen = 0;
  int32_t count = 0;
  int i, exit_code = 0;

  if (argc < 2 || argc > 3 || strcmp(argv[1], "--help") == 0) {
    fprintf(stderr, "usage: %s <source-uri> [config-yaml]\n", argv[0]);
    return argc == 2 ? 0 : 2;
  }
  printf("emf %s\n", emf_version_string());

  emf_runtime_options_init(&options);
  options.source_uri = argv[1];
  options.config_yaml = argc > 2 ? argv[2] : NULL;
  options.callback = onResult;
  options.user_data = &frames_seen;
  status = emf_runtime_create(&options, &runtime);
  if (status != EMF_OK) {
    fprintf(stderr, "error: %s: %s\n", emf_status_string(status), emf_last_error_message());
    return 1;
  }
  signal(SIGINT, onSignal);
  status = emf_runtime_start(runtime);
  if (status != EMF_OK) {
    fprintf(stderr, "error: %s: %s\n", emf_status_string(status), emf_last_error_message());
    emf_runtime_destroy(runtime);
    return 1;
  }

  memset(&result, 0, sizeof(result));
  result.struct_size = sizeof(result);
  objects[0].struct_size = sizeof(objects[0]);
  for (;;) {
    if (g_interrupted) {
      emf_runtime_stop(runtime); /* results already computed stay pollable */
      g_interrupted = 0;
    }
    status = emf_runtime_poll(runtime, 100, &result, objects, MAX_OBJECTS, &count);
    if (status == EMF_ERROR_TIMEOUT) continue;
    if (status == EMF_ERROR_DEVICE) { /* unplugged: the runtime retries; keep polling */
      fprintf(stderr, "sensor: %s\n", emf_last_error_message());
      continue;
    }
    if (status != EMF_OK) break;
    printf("frame %lld source=%lld t=%.6f lost=%d latency_ms=%.2f T_world_camera=",
           (long long)result.frame_index, (long long)result.source_index, result.timestamp,
           (int)result.tracking_lost, result.latency_ms);
    printPose(&result.T_world_camera);
    printf("\n");
    for (i = 0; i < count && i < MAX_OBJECTS; ++i) {
      printf("object %d class=%s state=%s T_world_object=", (int)objects[i].id,
             objects[i].class_name[0] ? objects[i].class_name : "-", stateName(objects[i].state));
      printPose(&objects[i].T_world_object);
      printf("\n");
    }
    fflush(stdout);
  }
  if (status != EMF_ERROR_END_OF_STREAM && status != EMF_ERROR_STATE) {
    fprintf(stderr, "error: %s: %s\n", emf_status_string(status), emf_last_error_message());
    exit_code = 1;
  }
  emf_runtime_stop(runtime);
  memset(&stats, 0, sizeof(stats));
  stats.struct_size = sizeof(stats);
  if (emf_runtime_get_stats(runtime, &stats) == EMF_OK) {
    printf("end frames=%lld produced=%lld dropped=%lld callbacks=%ld status=%s\n",
           (long long)stats.frames_processed, (long long)stats.frames_produced,
           (long long)stats.frames_dropped, frames_seen, emf_status_string(status));
  }
  emf_runtime_destroy(runtime);
  return exit_code;
}
