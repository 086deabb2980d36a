// The one interface every frame source implements: datasets (tum:, cofusion:, klg:), the
// synthetic world (synth:) and live sensors (openni2:, v4l2:). The pipeline cannot tell replay
// from live.
#pragma once

#include <memory>
#include <string>

#include "core/frame.h"
#include "core/source_options.h"

namespace emf::core {

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  /// Intrinsics of the depth image (valid after construction).
  virtual Intrinsics intrinsics() const = 0;
  /// Reads the next frame into `frame`. Returns false at the end of a recorded source. Throws
  /// IoError naming the file/line/frame on unreadable or inconsistent input.
  virtual bool next(Frame& frame) = 0;
  /// Number of frames if known (recorded sources), else -1.
  virtual int64_t size() const { return -1; }
  /// True for live sensors (frames arrive in real time; drop_oldest makes sense).
  virtual bool isLive() const { return false; }
  /// Frames the source itself dropped before next() returned them so far: a live sensor (or the
  /// virtual device) delivering faster than the caller reads, seen as gaps in its frame
  /// numbers. 0 for recorded sources.
  virtual int64_t droppedFrames() const { return 0; }
  /// Human-readable description ("TUM folder /data/x, 300 frames").
  virtual std::string describe() const = 0;
  /// Releases the device/files. Also done by the destructor.
  virtual void close() {}
};

}  // namespace emf::core
