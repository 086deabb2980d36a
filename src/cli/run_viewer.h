// What `emf run --view`, `--video FILE` and `--frames-png DIR` do with each processed frame: the
// SLAM thread hands a pipeline::ViewFrame over and goes on; a thread of the viewer composes the
// picture (pipeline::RunView) and shows it in a window and / or writes it. The window never
// holds the SLAM back: a frame that arrives while the previous one is still being drawn replaces
// it (counted as dropped). The video and the PNG sequence get every frame: the hand-over waits
// when kQueuedFrames are pending.
#pragma once

#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <opencv2/videoio.hpp>
#include <string>
#include <thread>

#include "pipeline/run_view.h"

namespace emf::cli {

struct RunViewerOptions {
  bool window = false;     // --view
  std::string video_path;  // --video: .avi (Motion JPEG) or .mp4 (MPEG-4 part 2)
  std::string png_dir;     // --frames-png: <dir>/<frame, 6 digits>.png
  double fps = 30.0;       // frame rate written into the video
};

class RunViewer {
 public:
  /// Frames written / shown may wait in a queue this long before the hand-over blocks.
  static constexpr size_t kQueuedFrames = 4;

  /// The checks that need no frame: a display for the window, a video name OpenCV can write
  /// (.avi / .mp4). Throws InvalidArgument naming the flag. (The constructor repeats them.)
  static void checkOptions(const RunViewerOptions& options);

  /// Checks everything before the first frame: a display for the window ($DISPLAY or
  /// $WAYLAND_DISPLAY), a video file OpenCV can encode with `frame_size` (the panel, see
  /// RunView), the PNG folder (created). Throws InvalidArgument / IoError naming the flag.
  RunViewer(const RunViewerOptions& options, cv::Size depth_size);
  /// Finishes (see finish()), swallowing its error.
  ~RunViewer();
  RunViewer(const RunViewer&) = delete;
  RunViewer& operator=(const RunViewer&) = delete;

  void submit(pipeline::ViewFrame frame);
  /// Draws / writes what is queued, closes the video and the window. Throws IoError for a
  /// frame that could not be written (the first error).
  void finish();

  int64_t framesShown() const;
  int64_t framesDropped() const;  // window only: replaced before they were drawn
  int64_t framesWritten() const;  // video / PNG

 private:
  void threadMain();
  void draw(const pipeline::ViewFrame& frame);

  RunViewerOptions options_;
  pipeline::RunView view_;
  cv::VideoWriter video_;
  bool window_open_ = false;

  mutable std::mutex mutex_;
  std::condition_variable wake_, space_;
  std::deque<pipeline::ViewFrame> queue_;
  bool done_ = false;
  int64_t shown_ = 0, dropped_ = 0, written_ = 0;
  std::string error_;
  std::thread thread_;
};

}  // namespace emf::cli
