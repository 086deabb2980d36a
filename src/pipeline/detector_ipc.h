// The protocol between emf and emf_detector_host, the child process that runs a detector plugin
// under process isolation (detector.isolation: process). One shared memory segment (a memfd)
// carries the frame in and the detections out; a socket pair carries one small Message each
// way per call, so the parent can wait with a deadline and sees the child's death as the
// socket's end. Both sides are built from this header: there is no version skew to handle.
//
// Segment layout (offsets in Header, 64-byte aligned):
//   Header | depth (float, w x h) | colour (BGR8, cw x ch) | background_association (float) |
//   residual (float) | kMaxDetections masks (float, w x h each)
#pragma once

#include <cstddef>
#include <cstdint>

namespace emf::pipeline::ipc {

constexpr uint32_t kMagic = 0x454d4644;  // "EMFD"
/// Detections carried back per call; more are dropped with a message in `rejected`.
constexpr int kMaxDetections = 64;
constexpr int kTextBytes = 1024;
constexpr int kClassNameBytes = 128;
constexpr int kRejectedKept = 8;  // messages of dropped detections carried back (count is exact)

/// File descriptors the child finds the segment and its socket on.
constexpr int kChildShmFd = 3;
constexpr int kChildSocketFd = 4;

enum class Op : uint32_t {
  kReady = 1,       // child -> parent: plugin loaded (Header: plugin_name, flags)
  kLoadFailed = 2,  // child -> parent: plugin not loaded (Header: error, status)
  kDetect = 3,      // parent -> child: run detect() on the request in the segment
  kDone = 4,        // child -> parent: response in the segment
};

struct Message {
  Op op;
  uint32_t reserved;
  int64_t seq;  // kDetect's number, echoed by kDone
};

struct DetectionRecord {
  int32_t id;
  float score;
  int32_t box_x, box_y, box_width, box_height;
  char class_name[kClassNameBytes];
};

struct Header {
  uint32_t magic;
  uint32_t reserved;
  uint64_t segment_bytes;  // the parent's current size (the child remaps when it changes)

  // Written by the child once the plugin is loaded (kReady / kLoadFailed).
  int32_t new_objects_only;
  int32_t reads_feedback;
  int32_t load_status;  // emf_status of a failed load
  char plugin_name[256];

  // Request (parent).
  int64_t frame_index;
  double timestamp;
  double rgb_timestamp;
  char timestamp_text[64];
  int32_t width, height;              // depth (and mask) size
  int32_t color_width, color_height;  // 0 x 0 = no colour
  int32_t has_background_association, has_residual;
  uint64_t depth_offset, color_offset, association_offset, residual_offset, masks_offset;

  // Response (child).
  int32_t count;           // detections in `detections`, masks at masks_offset + i * w * h
  int32_t rejected_count;  // detections the child's validation dropped
  int32_t response_new_objects_only;
  int32_t reserved2;
  char error[kTextBytes];  // "" = the call succeeded (also the load error)
  char rejected[kRejectedKept][256];
  DetectionRecord detections[kMaxDetections];
};

inline uint64_t align64(uint64_t v) { return (v + 63u) & ~uint64_t(63); }

/// Fills the offsets of `h` for a w x h depth image and a cw x ch colour image and returns the
/// segment size they need.
inline uint64_t layout(Header& h, int width, int height, int color_width, int color_height) {
  const uint64_t px = uint64_t(width) * uint64_t(height);
  uint64_t at = align64(sizeof(Header));
  h.depth_offset = at;
  at = align64(at + px * sizeof(float));
  h.color_offset = at;
  at = align64(at + uint64_t(color_width) * uint64_t(color_height) * 3u);
  h.association_offset = at;
  at = align64(at + px * sizeof(float));
  h.residual_offset = at;
  at = align64(at + px * sizeof(float));
  h.masks_offset = at;
  return at + uint64_t(kMaxDetections) * px * sizeof(float);
}

}  // namespace emf::pipeline::ipc
