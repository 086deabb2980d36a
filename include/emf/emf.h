/* emf — embedded real-time dynamic object-level RGB-D SLAM (EM-Fusion). Public C API.
 *
 * Conventions:
 * - Every function returns emf_status (EMF_OK = 0). On error, emf_last_error_message() returns
 *   a message for the calling thread that names what failed and what to do.
 * - Handles are opaque; create/destroy pairs; destroy(NULL) is a no-op.
 * - Every public struct starts with `struct_size`: set it to sizeof(struct) before the call.
 * - No C++ exception ever crosses this boundary.
 * - Thread safety is documented per function.
 */
#ifndef EMF_H
#define EMF_H

#include "emf_types.h"

#ifdef __cplusplus
extern "C" {
#endif

#define EMF_VERSION_MAJOR 0
#define EMF_VERSION_MINOR 1
#define EMF_VERSION_PATCH 0
/** Encoded version: major * 10000 + minor * 100 + patch. */
#define EMF_VERSION (EMF_VERSION_MAJOR * 10000 + EMF_VERSION_MINOR * 100 + EMF_VERSION_PATCH)
/** API version a caller is compiled against; passed in emf_system_options. A library accepts
 *  callers with the same major version and a minor version not newer than its own. */
#define EMF_API_VERSION EMF_VERSION

/** Runtime version of the library (EMF_VERSION encoding). Thread-safe. */
EMF_API uint32_t emf_version(void);
/** Runtime version as "major.minor.patch". Static storage. Thread-safe. */
EMF_API const char* emf_version_string(void);
/** Name of a status code, e.g. "EMF_ERROR_CONFIG". Static storage. Thread-safe. */
EMF_API const char* emf_status_string(emf_status status);
/** Message of the last failed emf_* call on this thread ("" if none). Valid until the next
 *  emf_* call on this thread. Thread-safe (thread-local). */
EMF_API const char* emf_last_error_message(void);

/** An emf system: configuration, OpenCL device, map, trackers. Opaque. */
typedef struct emf_system emf_system;

/** Options for emf_system_create. */
typedef struct emf_system_options {
  size_t struct_size;      /**< sizeof(emf_system_options) */
  uint32_t api_version;    /**< EMF_API_VERSION */
  const char* config_file; /**< YAML file (e.g. conf/default.yaml) or NULL for the defaults */
  const char*
      config_yaml; /**< YAML text applied on top (NULL = none), e.g. "map: {memory_mb: 128}" */
} emf_system_options;

/** Fills `options` with defaults (struct_size, api_version set; no config). */
EMF_API void emf_system_options_init(emf_system_options* options);

/** Creates a system: validates the configuration and selects the OpenCL device (PoCL CPU as
 *  fallback). On error *out is set to NULL. Thread-safe (different systems are independent). */
EMF_API emf_status emf_system_create(const emf_system_options* options, emf_system** out);
/** Destroys a system and frees everything it holds. NULL is a no-op. Not concurrent with other
 *  calls on the same system. */
EMF_API void emf_system_destroy(emf_system* system);

/** Facts about a created system. */
typedef struct emf_system_info {
  size_t struct_size;         /**< sizeof(emf_system_info) */
  char device_name[256];      /**< selected OpenCL device */
  char platform_name[256];    /**< its platform */
  int32_t device_is_fallback; /**< 1 if the configured device was not found */
} emf_system_info;

/** Fills `info` for `system`. Thread-safe with other reads. */
EMF_API emf_status emf_system_get_info(const emf_system* system, emf_system_info* info);

/* ---- Synchronous use: the integrator owns the loop ------------------------------------- */

/** One RGB-D frame in caller memory (only read during the call). Depth is required; colour is
 *  optional (color.data NULL). */
typedef struct emf_frame {
  size_t struct_size; /**< sizeof(emf_frame) */
  double timestamp;   /**< seconds (sensor clock); must increase from frame to frame */
  emf_image depth;    /**< EMF_PIXEL_DEPTH_U16 (with depth_scale) or EMF_PIXEL_DEPTH_F32, of the
                           intrinsics' size */
  double depth_scale; /**< uint16 units per metre (e.g. 1000 for mm, 5000 for TUM); ignored for
                           F32 */
  emf_image color;    /**< EMF_PIXEL_BGR8 or EMF_PIXEL_RGB8 (any size), or data NULL */
} emf_frame;

/** Fills `frame` with defaults (struct_size of the frame and both images, depth_scale 1000). */
EMF_API void emf_frame_init(emf_frame* frame);

/** Per-frame outcome. */
typedef struct emf_frame_result {
  size_t struct_size;      /**< sizeof(emf_frame_result) */
  int64_t frame_index;     /**< 0-based count of frames processed by this system / runtime */
  int64_t source_index;    /**< runtime: the source's frame index; sync: = frame_index */
  double timestamp;        /**< the frame's timestamp, seconds (sensor clock) */
  emf_pose T_world_camera; /**< camera pose in the world (= the first camera's frame) */
  int32_t tracking_lost;   /**< 1 if camera tracking failed (the frame was not integrated) */
  int32_t object_count;    /**< objects in this result (alive plus deleted in this frame) */
  double processing_ms;    /**< time spent in emf's SLAM for this frame (host clock) */
  /** Runtime only (else 0): host steady clock from the moment the capture thread put the frame
   *  into the frame ring (right after the source returned it) to the moment this result was
   *  complete (before the callback / poll queue). Excludes sensor exposure and driver transfer,
   *  whose sensor-clock timestamps are not comparable with the host clock. */
  double latency_ms;
  int64_t frames_dropped;      /**< runtime only: frames the ring dropped so far (drop_oldest) */
  int64_t pool_blocks_used;    /**< voxel pool slots in use after this frame */
  int64_t pool_blocks_dropped; /**< block allocations refused so far because the pool was full */
} emf_frame_result;

/** Object states. */
typedef enum emf_object_state {
  EMF_OBJECT_TRACKED = 1,   /**< tracked (and integrated) in this frame */
  EMF_OBJECT_INVISIBLE = 2, /**< alive but hidden behind nearer surfaces in this frame
                                 (objects.hidden_fraction) or leaving the view
                                 (objects.leaving_fraction): not tracked, its pose held still
                                 in the world, not integrated */
  EMF_OBJECT_DELETED = 3,   /**< deleted in this frame (reported once) */
  EMF_OBJECT_LOST = 4,      /**< tracking of the object failed in this frame: pose kept */
  EMF_OBJECT_DORMANT = 5    /**< retired by a rule (lost, left the view, ...) but its model kept
                                 for objects.reidentify_frames: a later detection that fits it
                                 re-attaches it with this id; reported DELETED when that ends.
                                 Not tracked, integrated or rendered; pose as last tracked */
} emf_object_state;

/** One object. In arrays the caller sets objects[0].struct_size; emf uses it as the element
 *  stride and writes the fields that fit. */
typedef struct emf_object_info {
  size_t struct_size;       /**< sizeof(emf_object_info) */
  int32_t id;               /**< stable id (> 0); the background is volume 0 */
  char class_name[64];      /**< detector class, e.g. "car" (NUL-terminated, truncated) */
  emf_object_state state;   /**< in the frame of the result */
  emf_pose T_world_object;  /**< object frame in the world (its volume frame at creation; stays
                                 on the object when the volume grows) */
  emf_pose T_object_camera; /**< camera in the object's frame (how objects are evaluated) */
  double existence;         /**< Ex / (Ex + NonEx), in [0, 1] */
  int64_t first_frame;      /**< first frame (frame_index) the object was tracked */
  int64_t last_frame;       /**< last frame (frame_index) the object was tracked */
} emf_object_info;

/** Counters of the fixed memory pool and the frame flow. */
typedef struct emf_stats {
  size_t struct_size;          /**< sizeof(emf_stats) */
  int64_t frames_processed;    /**< frames processed by the SLAM */
  int64_t frames_lost;         /**< of which camera tracking failed */
  int64_t pool_blocks_total;   /**< slots of the voxel pool */
  int64_t pool_blocks_used;    /**< slots in use */
  int64_t pool_blocks_dropped; /**< block allocations refused because the pool was full */
  int64_t pool_bytes;          /**< bytes of the one pool allocation */
  int64_t frames_produced;     /**< runtime only: frames the capture thread put into the ring */
  int64_t frames_dropped;      /**< runtime only: frames the ring dropped (drop_oldest) */
  int64_t results_dropped;     /**< runtime only: results discarded from the full poll queue */
  int64_t sensor_errors;       /**< runtime only: sensor disconnections reported */
  /* Appended later: callers with an older emf.h pass a smaller struct_size and get the fields
   * above. The detector_* fields from emf_system_get_stats only (0 from the runtime). */
  int64_t detector_runs;         /**< detector plugin calls finished */
  int64_t detector_failures;     /**< calls that gave no detections (plugin error, crash, hang) */
  int64_t detector_crashes;      /**< detector.isolation process: the plugin's process died */
  int64_t detector_timeouts;     /**< ... a call passed detector.deadline_s (process killed) */
  int64_t detector_restarts;     /**< ... the plugin's process was started again */
  int64_t source_frames_dropped; /**< runtime only: frames a live sensor delivered while the
                                      capture thread was busy (gaps in its frame numbers) */
} emf_stats;

/** Sets the depth camera intrinsics; required once before the first emf_system_process_frame
 *  (a second call returns EMF_ERROR_STATE: create a new system for another camera). Allocates
 *  the device state for frames of this size. Not concurrent with other calls on `system`. */
EMF_API emf_status emf_system_set_intrinsics(emf_system* system, const emf_intrinsics* intrinsics);

/** Processes one frame: tracking, association, mapping, object lifecycle (the detector plugin
 *  configured in detector.* runs on its schedule). `result` may be NULL. Errors: no intrinsics
 *  yet (EMF_ERROR_STATE), depth of another size than the intrinsics, unsupported pixel format,
 *  non-increasing timestamp (EMF_ERROR_INVALID_ARGUMENT). Not concurrent with other calls on
 *  `system`; the frame's memory is only read during the call. */
EMF_API emf_status emf_system_process_frame(emf_system* system, const emf_frame* frame,
                                            emf_frame_result* result);

/** Copies up to `capacity` objects of the last processed frame (alive, plus those deleted in it)
 *  into `objects` (may be NULL when capacity is 0) and their number into *count (which may
 *  exceed capacity: call again with a larger array). Thread-safe with other reads; not
 *  concurrent with emf_system_process_frame. */
EMF_API emf_status emf_system_get_objects(const emf_system* system, emf_object_info* objects,
                                          int32_t capacity, int32_t* count);

/** Pool and frame counters (the runtime fields are 0). Same thread rules as get_objects. */
EMF_API emf_status emf_system_get_stats(const emf_system* system, emf_stats* stats);

/** A triangle mesh owned by emf; free with emf_mesh_destroy. */
typedef struct emf_mesh {
  size_t struct_size;      /**< sizeof(emf_mesh) */
  int32_t vertex_count;    /**< vertices */
  const float* positions;  /**< 3 floats per vertex, metres, world frame */
  const float* normals;    /**< 3 floats per vertex, unit length, pointing to free space */
  int32_t triangle_count;  /**< triangles */
  const uint32_t* indices; /**< 3 vertex indices per triangle, counter-clockwise from outside */
} emf_mesh;

/** Extracts the mesh of volume `volume_id` (0 = background, else an object id) in world
 *  coordinates (objects at their current pose) into a new mesh (*out; NULL on error). The
 *  background's mesh includes the surface of the blocks its grid left while following the
 *  camera (map.follow_camera; kept on disk in the system's temporary folder until then).
 *  EMF_ERROR_NOT_FOUND for an unknown id, EMF_ERROR_STATE before set_intrinsics. Not
 *  concurrent with emf_system_process_frame. */
EMF_API emf_status emf_system_extract_mesh(emf_system* system, int32_t volume_id, emf_mesh** out);
/** Frees a mesh. NULL is a no-op. Thread-safe for distinct meshes. */
EMF_API void emf_mesh_destroy(emf_mesh* mesh);
/** Writes the mesh of `volume_id` to a binary PLY file with normals, atomically (temporary files
 *  in the same folder, then rename). Streamed: the mesh is never held in memory as a whole.
 *  Same rules as emf_system_extract_mesh. */
EMF_API emf_status emf_system_save_mesh(emf_system* system, int32_t volume_id, const char* path);

/** Renders the map (background and rendered objects) from a camera pose (NULL = the current
 *  camera) with the system's intrinsics into caller buffers of width * height elements
 *  (row-major, tightly packed): depth (float metres along the camera z axis, NaN = nothing),
 *  volume ids (int32, -1 = nothing, 0 = background, else object id). Either buffer may be NULL.
 *  A pose that is not finite or whose R is not a rotation (to 1e-4) is EMF_ERROR_INVALID_ARGUMENT.
 *  Not concurrent with other calls on `system`. */
EMF_API emf_status emf_system_render(emf_system* system, const emf_pose* T_world_camera,
                                     float* depth_m, int32_t* volume_ids);

/** The association map of the last processed frame for one volume (0 = background, else an
 *  object id): q(u) in [0, 1], the probability that the depth measured at pixel u belongs to
 *  that volume (the E-step's posterior, the paper's q_0 / q_i), NaN where the frame had no
 *  depth. Written into `q` as width * height floats, row-major, tightly packed (the
 *  intrinsics' size; the buffer is the caller's). The next emf_system_process_frame replaces
 *  the map this call reads. Together with
 *  emf_system_render's volume ids (the rendered object masks at the current pose) this is what
 *  `emf run --view` draws. EMF_ERROR_NOT_FOUND when no E-step ran in the last frame (no object
 *  alive and no detection) or `volume_id` was not in it; EMF_ERROR_STATE before the first
 *  frame. Not concurrent with other calls on `system`. */
EMF_API emf_status emf_system_get_association(const emf_system* system, int32_t volume_id,
                                              float* q);

/* ---- Runtime: emf owns the loop (capture thread -> frame ring -> SLAM thread) ---------- */

/** A runtime: a source, its capture thread, the frame ring, the SLAM thread. Opaque. */
typedef struct emf_runtime emf_runtime;

/** Called on the SLAM thread after every processed frame, in frame order. Must return quickly
 *  (it delays the next frame); must not call emf_runtime_stop / emf_runtime_destroy. The
 *  pointers are valid only during the call. */
typedef void (*emf_result_callback)(const emf_frame_result* result, const emf_object_info* objects,
                                    int32_t object_count, void* user_data);

/** Options for emf_runtime_create. */
typedef struct emf_runtime_options {
  size_t struct_size;           /**< sizeof(emf_runtime_options) */
  uint32_t api_version;         /**< EMF_API_VERSION */
  const char* source_uri;       /**< tum:<dir>, synth:<preset>, openni2:[uri], v4l2:/dev/videoN,
                                     ...; NULL = the config's source.uri */
  const char* config_file;      /**< YAML file or NULL for the defaults */
  const char* config_yaml;      /**< YAML applied on top (NULL = none), e.g. the ring:
                                     "runtime: {ring_policy: drop_oldest, ring_slots: 4}" */
  emf_result_callback callback; /**< may be NULL (use emf_runtime_poll) */
  void* user_data;              /**< passed to the callback */
} emf_runtime_options;

/** Fills `options` with defaults (struct_size, api_version; no source, no callback). */
EMF_API void emf_runtime_options_init(emf_runtime_options* options);

/** Opens the source (reads its first frame to size the frame ring), selects the OpenCL device
 *  and builds the SLAM system; does not start threads. On error *out is NULL. Thread-safe
 *  (runtimes are independent). */
EMF_API emf_status emf_runtime_create(const emf_runtime_options* options, emf_runtime** out);

/** Starts the capture and SLAM threads. No-op while running or after the end of the stream;
 *  EMF_ERROR_STATE after emf_runtime_stop, whatever the state (a runtime is not restartable). Call
 * start, stop and destroy from one controlling thread. */
EMF_API emf_status emf_runtime_start(emf_runtime* runtime);

/** Waits up to timeout_ms (0 = do not wait) for the next result and copies it into `result`
 *  (may be NULL) and up to `capacity` of its objects into `objects` (*count = their total
 *  number; count may be NULL). The queue keeps the newest runtime.result_queue results: a
 *  slower poller loses the oldest (emf_stats.results_dropped). Returns EMF_OK with a result;
 *  EMF_ERROR_TIMEOUT when none arrived; EMF_ERROR_END_OF_STREAM when a recorded source is
 *  exhausted and every result was polled; EMF_ERROR_DEVICE when no result is queued and the
 *  live sensor is disconnected (returned as soon as it disconnects during the wait, or at the
 *  timeout while it stays away; the runtime keeps running and resumes when the sensor is back);
 *  EMF_ERROR_STATE before emf_runtime_start and after stop once the queue is empty; the error of a
 * fatal failure (e.g. EMF_ERROR_IO for an unreadable dataset file) once the queue is empty.
 * Thread-safe. */
EMF_API emf_status emf_runtime_poll(emf_runtime* runtime, int32_t timeout_ms,
                                    emf_frame_result* result, emf_object_info* objects,
                                    int32_t capacity, int32_t* count);

/** Stops and joins both threads (idempotent, also from two threads at once; bounded by the
 *  source's frame timeout). Frames
 *  still in the ring are discarded; results already queued stay pollable. Not from the
 *  callback. */
EMF_API emf_status emf_runtime_stop(emf_runtime* runtime);

/** Counters of the frame flow and the pool (a consistent snapshot). Thread-safe, any time. */
EMF_API emf_status emf_runtime_get_stats(const emf_runtime* runtime, emf_stats* stats);

/** The system inside the runtime, for meshes, renders, objects and stats. Owned by the runtime
 *  (valid until emf_runtime_destroy; emf_system_destroy on it is a no-op). Its calls return
 *  EMF_ERROR_STATE while the runtime is running: use it after the end of the stream or after
 *  emf_runtime_stop. emf_system_process_frame / set_intrinsics on it are always
 *  EMF_ERROR_STATE. NULL for a NULL runtime. */
EMF_API emf_system* emf_runtime_system(emf_runtime* runtime);

/** Stops and destroys. NULL is a no-op. Not from the callback. A poll blocked in another thread
 *  returns EMF_ERROR_STATE, and destroy waits until the polls and get_stats calls in flight have
 *  returned before it frees the runtime; no call on it may start once destroy has begun. */
EMF_API void emf_runtime_destroy(emf_runtime* runtime);

#ifdef __cplusplus
}
#endif

#endif /* EMF_H */
