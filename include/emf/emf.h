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
  size_t struct_size;   /**< sizeof(emf_system_options) */
  uint32_t api_version; /**< EMF_API_VERSION */
  const char* config_file; /**< YAML file (e.g. conf/default.yaml) or NULL for the defaults */
  const char* config_yaml; /**< YAML text applied on top (NULL = none), e.g. "map: {memory_mb: 128}" */
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
  size_t struct_size;      /**< sizeof(emf_system_info) */
  char device_name[256];   /**< selected OpenCL device */
  char platform_name[256]; /**< its platform */
  int32_t device_is_fallback; /**< 1 if the configured device was not found */
} emf_system_info;

/** Fills `info` for `system`. Thread-safe with other reads. */
EMF_API emf_status emf_system_get_info(const emf_system* system, emf_system_info* info);

#ifdef __cplusplus
}
#endif

#endif /* EMF_H */
