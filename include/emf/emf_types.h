/* emf — public C types: status codes, images, intrinsics, poses.
 * C99, no third-party headers. Every struct that may grow starts with `struct_size`
 * (set it to sizeof(the struct) you were compiled with) so fields can be appended. The smallest
 * struct_size emf accepts is the struct's size in the first release (this header's: no field
 * has been appended yet); emf writes or reads the fields a caller's struct_size covers. */
#ifndef EMF_TYPES_H
#define EMF_TYPES_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(_WIN32)
#define EMF_API __declspec(dllexport)
#elif defined(__GNUC__)
#define EMF_API __attribute__((visibility("default")))
#else
#define EMF_API
#endif

/** Result of every emf_* call. EMF_OK is 0; errors are negative. */
typedef enum emf_status {
  EMF_OK = 0,
  EMF_ERROR_INVALID_ARGUMENT = -1, /**< NULL where not allowed, bad struct_size, bad value */
  EMF_ERROR_VERSION_MISMATCH = -2, /**< caller's API version is not supported by this library */
  EMF_ERROR_CONFIG = -3,           /**< configuration file/key/value rejected */
  EMF_ERROR_IO = -4,               /**< file or dataset unreadable / unwritable */
  EMF_ERROR_OPENCL = -5,           /**< no OpenCL device, kernel build or enqueue failure */
  EMF_ERROR_OUT_OF_MEMORY = -6,    /**< an allocation or the voxel pool budget failed */
  EMF_ERROR_NOT_FOUND = -7,        /**< no such object, device, plugin or source */
  EMF_ERROR_DEVICE = -8,           /**< a sensor failed or was unplugged */
  EMF_ERROR_STATE = -9,            /**< call not valid in the current state (e.g. not started) */
  EMF_ERROR_TIMEOUT = -10,         /**< nothing arrived within the given time */
  EMF_ERROR_END_OF_STREAM = -11,   /**< a recorded source has no more frames */
  EMF_ERROR_INTERNAL = -99         /**< a bug in emf: please report with the message */
} emf_status;

/** Pinhole intrinsics of the depth image (pixels). */
typedef struct emf_intrinsics {
  double fx, fy, cx, cy;
  int32_t width, height;
} emf_intrinsics;

/** A rigid transform T_a_b mapping points in frame b to frame a: row-major 3x4 [R | t],
 *  translation in metres. */
typedef struct emf_pose {
  double m[12];
} emf_pose;

/** Pixel formats of caller-owned images. */
typedef enum emf_pixel_format {
  EMF_PIXEL_DEPTH_U16 = 1, /**< uint16 depth, metres = value / depth_scale, 0 = invalid */
  EMF_PIXEL_DEPTH_F32 = 2, /**< float depth in metres, 0 or NaN = invalid */
  EMF_PIXEL_RGB8 = 3,      /**< 8-bit R, G, B interleaved */
  EMF_PIXEL_BGR8 = 4,      /**< 8-bit B, G, R interleaved */
  EMF_PIXEL_GRAY8 = 5,     /**< 8-bit single channel */
  EMF_PIXEL_F32 = 6        /**< float single channel */
} emf_pixel_format;

/** A view of caller-owned pixels; emf never frees or keeps it beyond the call. */
typedef struct emf_image {
  size_t struct_size;
  emf_pixel_format format;
  int32_t width, height;
  size_t stride_bytes; /**< bytes per row; 0 = tightly packed */
  const void* data;
} emf_image;

#ifdef __cplusplus
}
#endif

#endif /* EMF_TYPES_H */
