#include "cli/run_viewer.h"

#include <netdb.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <opencv2/highgui.hpp>

#include "common/error.h"
#include "io/atomic_output.h"

namespace emf::cli {
namespace {

constexpr const char* kWindow = "emf run";

// Whether the X display named by $DISPLAY accepts a connection ("" = yes, else why not): its
// toolkit (Qt or GTK) would otherwise abort the process in the middle of the run. Local
// displays (":N") are the socket /tmp/.X11-unix/XN, others ("host:N", ssh's "localhost:10")
// TCP port 6000 + N.
std::string displayProblem(const std::string& display) {
  const size_t colon = display.rfind(':');
  if (colon == std::string::npos) return "DISPLAY='" + display + "' has no ':<number>'";
  const std::string host = display.substr(0, colon);
  const int number = std::atoi(display.c_str() + colon + 1);
  int fd = -1;
  int rc = -1;
  if (host.empty() || host == "unix") {
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::snprintf(addr.sun_path, sizeof(addr.sun_path), "/tmp/.X11-unix/X%d", number);
    fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd >= 0) rc = ::connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof(addr));
  } else {
    addrinfo hints{};
    hints.ai_socktype = SOCK_STREAM;
    addrinfo* found = nullptr;
    if (::getaddrinfo(host.c_str(), std::to_string(6000 + number).c_str(), &hints, &found) == 0) {
      for (addrinfo* a = found; a && rc != 0; a = a->ai_next) {
        if (fd >= 0) ::close(fd);
        fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
        if (fd >= 0) rc = ::connect(fd, a->ai_addr, a->ai_addrlen);
      }
      ::freeaddrinfo(found);
    }
  }
  const int err = errno;
  if (fd >= 0) ::close(fd);
  return rc == 0 ? "" : "cannot connect to the X display '" + display + "': " + std::strerror(err);
}

}  // namespace

void RunViewer::checkOptions(const RunViewerOptions& options) {
  if (options.window) {
    const char* x = std::getenv("DISPLAY");
    const char* wayland = std::getenv("WAYLAND_DISPLAY");
    if (!(x && *x) && !(wayland && *wayland)) {
      throw InvalidArgument(
          "--view needs a display ($DISPLAY is not set: no X server, e.g. over ssh); use "
          "--video FILE or --frames-png DIR to see the run afterwards");
    }
    if (x && *x) {
      const std::string problem = displayProblem(x);
      if (!problem.empty()) {
        throw InvalidArgument("--view: " + problem +
                              "; start the X server or fix $DISPLAY, or use --video FILE or "
                              "--frames-png DIR");
      }
    }
  }
  if (!options.video_path.empty()) {
    const std::string ext = std::filesystem::path(options.video_path).extension().string();
    if (ext != ".avi" && ext != ".mp4") {
      throw InvalidArgument("--video " + options.video_path +
                            ": the name must end in .avi (Motion JPEG) or .mp4 (MPEG-4)");
    }
  }
}

RunViewer::RunViewer(const RunViewerOptions& options, cv::Size depth_size) : options_(options) {
  checkOptions(options_);
  const cv::Size panel(depth_size.width / 2 * 3, depth_size.height / 2 * 3);
  if (!options_.video_path.empty()) {
    const std::string ext = std::filesystem::path(options_.video_path).extension().string();
    const int fourcc = ext == ".avi" ? cv::VideoWriter::fourcc('M', 'J', 'P', 'G')
                                     : cv::VideoWriter::fourcc('m', 'p', '4', 'v');
    const std::filesystem::path parent = std::filesystem::path(options_.video_path).parent_path();
    std::error_code ec;
    if (!parent.empty()) std::filesystem::create_directories(parent, ec);
    if (!video_.open(options_.video_path, fourcc, options_.fps, panel, true)) {
      throw IoError("--video " + options_.video_path +
                    ": OpenCV cannot write this file (a folder that is not writable, or no " + ext +
                    " encoder in its video backend; .avi always works)");
    }
  }
  if (!options_.png_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(options_.png_dir, ec);
    if (ec || !std::filesystem::is_directory(options_.png_dir)) {
      throw IoError("--frames-png " + options_.png_dir + ": cannot create the folder" +
                    (ec ? ": " + ec.message() : std::string()));
    }
  }
  thread_ = std::thread([this] { threadMain(); });
}

RunViewer::~RunViewer() {
  try {
    finish();
  } catch (const std::exception&) {
    // finish() was called by the owner when it wanted the error.
  }
}

void RunViewer::submit(pipeline::ViewFrame frame) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (done_) return;
  const bool writes = video_.isOpened() || !options_.png_dir.empty();
  if (writes) {
    space_.wait(lock, [this] { return queue_.size() < kQueuedFrames || done_; });
  } else if (!queue_.empty()) {
    dropped_ += static_cast<int64_t>(queue_.size());  // the window shows the newest only
    queue_.clear();
  }
  queue_.push_back(std::move(frame));
  wake_.notify_one();
}

void RunViewer::finish() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    done_ = true;
  }
  wake_.notify_all();
  space_.notify_all();
  if (thread_.joinable()) thread_.join();
  if (video_.isOpened()) video_.release();
  std::lock_guard<std::mutex> lock(mutex_);
  if (!error_.empty()) {
    const std::string e = error_;
    error_.clear();
    throw IoError(e);
  }
}

void RunViewer::draw(const pipeline::ViewFrame& frame) {
  const cv::Mat panel = view_.compose(frame);
  if (video_.isOpened()) video_.write(panel);
  if (!options_.png_dir.empty()) {
    char name[32];
    std::snprintf(name, sizeof(name), "/%06lld.png", static_cast<long long>(frame.index));
    io::writeImageAtomically(options_.png_dir + name, panel);
  }
  if (options_.window) {
    if (!window_open_ && shown_ == 0) {
      // 1:1 pixels, no toolbar (Qt builds of OpenCV add one otherwise).
      cv::namedWindow(kWindow, cv::WINDOW_AUTOSIZE | cv::WINDOW_GUI_NORMAL);
      window_open_ = true;
    }
    if (window_open_) {
      cv::imshow(kWindow, panel);
      const int key = cv::waitKey(1);
      // 'q' or Esc closes the window; the run goes on (and its video, if any).
      if (key == 'q' || key == 27 || cv::getWindowProperty(kWindow, cv::WND_PROP_VISIBLE) < 1) {
        cv::destroyWindow(kWindow);
        window_open_ = false;
      }
    }
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (options_.window && window_open_) ++shown_;
  if (video_.isOpened() || !options_.png_dir.empty()) ++written_;
}

void RunViewer::threadMain() {
  for (;;) {
    pipeline::ViewFrame frame;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return !queue_.empty() || done_; });
      if (queue_.empty()) break;  // done and drained
      frame = std::move(queue_.front());
      queue_.pop_front();
      space_.notify_one();
    }
    try {
      draw(frame);
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (error_.empty()) {
        error_ = "viewer, frame " + std::to_string(frame.index) + ": " + e.what();
      }
    }
  }
  if (window_open_) {
    cv::destroyWindow(kWindow);
    cv::waitKey(1);
    window_open_ = false;
  }
}

int64_t RunViewer::framesShown() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return shown_;
}
int64_t RunViewer::framesDropped() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return dropped_;
}
int64_t RunViewer::framesWritten() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return written_;
}

}  // namespace emf::cli
