/* emf — the detector plugin ABI (C99, versioned).
 *
 * A plugin is a shared object exporting one function, EMF_DETECTOR_ENTRY_SYMBOL:
 *
 *   EMF_DETECTOR_EXPORT const emf_detector_api* emf_detector_entry(uint32_t host_abi_version);
 *
 * It returns its function table, or NULL if it cannot serve a host of that ABI version. The host
 * checks abi_version and struct_size before using the table, and validates every result
 * (mask size, score range, box inside the image). A plugin that cannot be found, loaded or
 * created is an error when the system starts (emf_system_set_intrinsics, emf_runtime_create or
 * `emf run`: EMF_ERROR_NOT_FOUND, EMF_ERROR_IO, EMF_ERROR_VERSION_MISMATCH, or the status the
 * plugin's create() returned). A detect() that fails or returns garbage gets a clear message
 * and the SLAM keeps running without that detection.
 *
 * Ownership: results returned by detect() belong to the plugin until the host passes them back
 * to release(). Images in emf_detector_frame belong to the host and are valid only during the
 * detect() call.
 * Threading: the host calls create/detect/release/destroy of one emf_detector from one thread at
 * a time (possibly a dedicated detector thread); different instances may run concurrently.
 * Errors: functions return emf_status and may write a NUL-terminated message into `error`
 * (capacity `error_size`). No C++ exception may leave a plugin function.
 */
#ifndef EMF_DETECTOR_H
#define EMF_DETECTOR_H

#include "emf_types.h"

#ifdef __cplusplus
extern "C" {
#endif

/** ABI version of this header. Bumped when a field is removed or changes meaning; appended
 *  fields keep the version (struct_size tells what a peer knows). */
#define EMF_DETECTOR_ABI_VERSION 1u
/** Name of the one exported entry function. */
#define EMF_DETECTOR_ENTRY_SYMBOL "emf_detector_entry"

#if defined(__GNUC__)
#define EMF_DETECTOR_EXPORT __attribute__((visibility("default")))
#else
#define EMF_DETECTOR_EXPORT
#endif

/** Plugin-defined state of one detector instance. */
typedef struct emf_detector emf_detector;

/** What the host tells a detector at creation. */
typedef struct emf_detector_create_info {
  size_t struct_size;     /**< sizeof(emf_detector_create_info) */
  const char* config;     /**< plugin configuration string ("" if none); format is the plugin's */
  const char* source_uri; /**< URI of the frame source (e.g. "tum:/data/seq"); may be "" */
  emf_intrinsics intrinsics; /**< depth camera intrinsics */
} emf_detector_create_info;

/** One RGB-D frame given to detect(). */
typedef struct emf_detector_frame {
  size_t struct_size;  /**< sizeof(emf_detector_frame) */
  int64_t frame_index; /**< 0-based index in the source */
  double timestamp;    /**< depth timestamp, seconds */
  const char*
      timestamp_text; /**< the depth timestamp as the source wrote it (dataset file names) */
  emf_image depth;    /**< EMF_PIXEL_DEPTH_F32, metres, NaN or 0 = invalid */
  emf_image color;    /**< EMF_PIXEL_BGR8; data may be NULL when the source has no colour */
  /** Optional feedback from the SLAM (data NULL when not provided), same size as depth:
   *  background_association: EMF_PIXEL_F32 in [0, 1], how well the background explains u:
   *    the E-step's q_0(u), capped by the posterior of the background's inlier term against the
   *    uniform outlier (q_0 alone is 1 wherever only the background reaches), and 1 where the
   *    point lies behind the background's surface by more than em.sigma_m (a disocclusion:
   *    something that stood there moved away);
   *  residual: EMF_PIXEL_F32, |psi| of the best-associated volume in metres (NaN = none). */
  emf_image background_association;
  emf_image residual;
} emf_detector_frame;

/** One detected instance. The mask has the depth image's size. */
typedef struct emf_detection {
  size_t struct_size;                          /**< sizeof(emf_detection) */
  const char* class_name;                      /**< e.g. "car"; owned by the plugin */
  float score;                                 /**< confidence in [0, 1] */
  int32_t box_x, box_y, box_width, box_height; /**< pixels, inside the image */
  int32_t mask_width, mask_height;             /**< must equal the depth image size */
  const uint8_t* mask;           /**< binary mask (0 / non-zero), row-major; or NULL */
  const float* mask_probability; /**< per-pixel foreground probability in [0, 1]; or NULL.
                                      One of mask / mask_probability must be set; the
                                      probability wins when both are. */
} emf_detection;

/** The result of one detect() call. */
typedef struct emf_detection_result {
  size_t struct_size; /**< sizeof(emf_detection_result) */
  int32_t count;      /**< number of detections */
  /** count entries, each detections[0].struct_size bytes after the previous one (a plugin
   *  built against a newer header, with fields appended to emf_detection, steps by its own
   *  size); every entry's struct_size must be the same. */
  const emf_detection* detections;
} emf_detection_result;

/** The plugin's function table. */
typedef struct emf_detector_api {
  size_t struct_size;   /**< sizeof(emf_detector_api) as the plugin was compiled */
  uint32_t abi_version; /**< EMF_DETECTOR_ABI_VERSION the plugin was compiled against */
  const char* name;     /**< short name, e.g. "maskfile" */
  const char* description;
  /** Creates an instance. On failure returns an error status and a message in `error`. */
  emf_status (*create)(const emf_detector_create_info* info, emf_detector** out, char* error,
                       size_t error_size);
  /** Detects instances in `frame`. *out is set to a result the host later passes to release()
   *  (or NULL when there is nothing to release). */
  emf_status (*detect)(emf_detector* detector, const emf_detector_frame* frame,
                       emf_detection_result** out, char* error, size_t error_size);
  /** Releases a result returned by detect(). NULL is a no-op. */
  void (*release)(emf_detector* detector, emf_detection_result* result);
  /** Destroys an instance. NULL is a no-op. */
  void (*destroy)(emf_detector* detector);
  /** EMF_DETECTOR_FLAG_* bits. Added after the first release: the host reads it only when
   *  struct_size covers it, so a plugin built without it means 0. */
  uint32_t flags;
} emf_detector_api;

/** The detector reports only what the SLAM does not explain yet (e.g. `motion`): an existing
 *  object it does not detect is no evidence that the object is gone, so the host does not
 *  count NonEx for it (docs/method.md#matching). Without the flag every unmatched object gets
 *  NonEx += 1 per call. */
#define EMF_DETECTOR_FLAG_NEW_OBJECTS_ONLY 0x1u
/** The detector reads the SLAM feedback of emf_detector_frame (residual,
 *  background_association). Without the flag the host does not compute it (saves downloads and
 *  a background SDF probe per call) and passes those images with data NULL. Plugins built
 *  before the flags field existed get the feedback. */
#define EMF_DETECTOR_FLAG_READS_FEEDBACK 0x2u

/** Type of the entry function. */
typedef const emf_detector_api* (*emf_detector_entry_fn)(uint32_t host_abi_version);

#ifdef __cplusplus
}
#endif

#endif /* EMF_DETECTOR_H */
