#include "pipeline/detector_scheduler.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <exception>
#include <filesystem>

#include "common/error.h"
#include "common/log.h"
#include "pipeline/plugin_search_path.h"

namespace emf::pipeline {
namespace fs = std::filesystem;

namespace {

// Object poses kept per slot without reallocating (more objects still work, they allocate).
constexpr size_t kReservedObjects = 64;
// Timestamp text capacity reserved in the slot (source timestamps are ~20 characters).
constexpr size_t kReservedStampChars = 64;
// An isolated plugin's create() may load a model: it gets this long before it counts as hung.
constexpr double kLoadTimeoutS = 120.0;

// Copies `src` into `dst`, reusing dst's buffer when size and type match.
void copyInto(const cv::Mat& src, cv::Mat* dst) {
  if (src.empty()) {
    dst->release();
    return;
  }
  src.copyTo(*dst);
}

}  // namespace

bool usesProcess(const DetectorOptions& options, const std::string& resolved_path) {
  if (options.isolation == DetectorIsolation::kProcess) return true;
  if (options.isolation == DetectorIsolation::kNone) return false;
  std::error_code ec;
  const fs::path plugin = fs::weakly_canonical(resolved_path, ec);
  for (const std::string& folder : modulePluginFolders()) {
    if (fs::weakly_canonical(folder, ec) == plugin.parent_path()) return false;
  }
  return true;
}

std::string problemKind(const std::string& message) {
  std::string out;
  out.reserve(message.size());
  bool in_number = false;
  for (const char c : message) {
    if (std::isdigit(static_cast<unsigned char>(c))) {
      if (!in_number) out += '#';
      in_number = true;
    } else {
      out += c;
      in_number = false;
    }
  }
  return out;
}

DetectorScheduler::DetectorScheduler(const DetectorOptions& options, const std::string& source_uri,
                                     const core::Intrinsics& intrinsics) {
  if (!options.plugin.empty() &&
      usesProcess(options, resolvePluginPath(options.plugin, pluginSearchPath(options)))) {
    isolated_ = std::make_unique<IsolatedDetector>(
        detectorHostPath(), resolvePluginPath(options.plugin, pluginSearchPath(options)),
        options.plugin_config, source_uri, intrinsics, options.deadline_s, kLoadTimeoutS,
        // Sequential: the SLAM thread waits for the child, which must not yield to others.
        options.mode == DetectorMode::kAsync ? options.nice : 0);
    IsolatedDetector* isolated = isolated_.get();
    detect_ = [isolated](const core::Frame& f, const cv::Mat* q0, const cv::Mat* residual) {
      return isolated->detect(f, q0, residual);
    };
    name_ = isolated_->name();
    stats_.isolation = "process";
  } else if (!options.plugin.empty()) {
    plugin_ = DetectorPlugin::load(options.plugin, pluginSearchPath(options), options.plugin_config,
                                   source_uri, intrinsics);
    plugin_->setLogProblems(false);  // logged once per kind by recordProblem()
    DetectorPlugin* plugin = plugin_.get();
    detect_ = [plugin](const core::Frame& f, const cv::Mat* q0, const cv::Mat* residual) {
      return plugin->detect(f, q0, residual);
    };
    name_ = plugin_->name();
  }
  init(options, intrinsics);
}

DetectorScheduler::DetectorScheduler(const DetectorOptions& options, const std::string& name,
                                     DetectFunction detect, const core::Intrinsics& intrinsics)
    : detect_(std::move(detect)), name_(name) {
  init(options, intrinsics);
}

void DetectorScheduler::init(const DetectorOptions& options, const core::Intrinsics& intrinsics) {
  if (options.every_n_frames < 1) {
    throw ConfigError("detector.every_n_frames: " + std::to_string(options.every_n_frames) +
                      " must be >= 1 (set detector.every_n_frames)");
  }
  async_ = options.mode == DetectorMode::kAsync;
  every_n_frames_ = options.every_n_frames;
  nice_ = options.nice;
  stats_.plugin = name_;
  stats_.mode = choiceName(options.mode, detectorModeNames());
  if (!enabled() || !async_) return;
  // Preallocate the hand-over slot at the camera's size (colour assumed registered to depth;
  // another colour size reallocates once on the first frame).
  if (intrinsics.width > 0 && intrinsics.height > 0) {
    slot_.frame.depth.create(intrinsics.height, intrinsics.width, CV_32F);
    slot_.frame.color.create(intrinsics.height, intrinsics.width, CV_8UC3);
    slot_.background_association.create(intrinsics.height, intrinsics.width, CV_32F);
    slot_.residual.create(intrinsics.height, intrinsics.width, CV_32F);
  }
  slot_.frame.timestamp_text.reserve(kReservedStampChars);
  slot_.objects.reserve(kReservedObjects);
  working_.objects.reserve(kReservedObjects);
  ready_.objects.reserve(kReservedObjects);
  thread_ = std::thread([this] { threadMain(); });
}

DetectorScheduler::~DetectorScheduler() {
  if (thread_.joinable()) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }
}

void DetectorScheduler::recordProblem(const std::string& message) {
  const std::string kind = problemKind(message);
  int64_t& count = stats_.problems[kind];
  if (count++ == 0) {
    logWarning(message, " (further problems of this kind are only counted)");
  }
}

void DetectorScheduler::runDetector(const Slot& slot, DetectionBatch* batch) {
  batch->frame_index = slot.frame.index;
  batch->timestamp = slot.frame.timestamp;
  batch->timestamp_text = slot.frame.timestamp_text;
  batch->T_world_camera = slot.T_world_camera;
  batch->objects = slot.objects;
  batch->frames_late = 0;
  const auto t0 = std::chrono::steady_clock::now();
  DetectorOutput out;
  try {
    out = detect_(slot.frame,
                  slot.has_background_association ? &slot.background_association : nullptr,
                  slot.has_residual ? &slot.residual : nullptr);
  } catch (const std::exception& e) {
    out = DetectorOutput();
    out.error = "detector '" + name_ + "' frame " + std::to_string(slot.frame.index) +
                ": detect threw: " + e.what();
  } catch (...) {
    out = DetectorOutput();
    out.error = "detector '" + name_ + "' frame " + std::to_string(slot.frame.index) +
                ": detect threw an unknown exception";
  }
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  batch->detector_ms = ms;
  batch->detections = std::move(out.detections);
  batch->new_objects_only = out.new_objects_only;
  std::lock_guard<std::mutex> lock(mutex_);
  ++stats_.runs;
  if (isolated_) {
    const IsolationCounters c = isolated_->counters();
    stats_.crashes = c.crashes;
    stats_.timeouts = c.timeouts;
    stats_.restarts = c.restarts;
  }
  detector_ms_.push_back(ms);
  stats_.detections += static_cast<int64_t>(batch->detections.size());
  stats_.rejected += static_cast<int64_t>(out.rejected.size());
  for (const auto& r : out.rejected) recordProblem(r);
  if (!out.error.empty()) {
    ++stats_.failures;
    recordProblem(out.error + "; continuing without detections");
  }
}

void DetectorScheduler::threadMain() {
  // Linux: PRIO_PROCESS with a thread id sets that thread's niceness; the threads it starts
  // inherit it.
  if (nice_ > 0 &&
      ::setpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)), nice_) != 0) {
    logWarning("detector: cannot set the detector thread's niceness to ", nice_, " (",
               std::strerror(errno), "); it runs at the SLAM's priority");
  }
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return stop_ || busy_; });
    if (stop_) return;
    lock.unlock();
    runDetector(slot_, &working_);  // slot_ and working_ are ours while busy_
    lock.lock();
    std::swap(ready_, working_);
    has_ready_ = true;
    busy_ = false;
    idle_.notify_all();
  }
}

std::optional<DetectionBatch> DetectorScheduler::takeReady(int64_t current_index) {
  if (!has_ready_) return std::nullopt;
  has_ready_ = false;
  ++stats_.results_delivered;
  std::optional<DetectionBatch> out(std::move(ready_));
  ready_ = DetectionBatch();
  out->frames_late = current_index >= out->frame_index ? current_index - out->frame_index : 0;
  return out;
}

std::optional<DetectionBatch> DetectorScheduler::submit(const core::Frame& frame,
                                                        const Eigen::Isometry3d& T_world_camera,
                                                        const cv::Mat* background_association,
                                                        const cv::Mat* residual,
                                                        const std::vector<ObjectPose>* objects) {
  if (!enabled()) {
    if (frame.detections && !frame.detections->empty() && !warned_source_detections_) {
      warned_source_detections_ = true;
      logInfo("frame ", frame.index,
              " carries detections from the source; they are not used without a detector "
              "plugin (use --detector maskfile to replay them)");
    }
    return std::nullopt;
  }
  const bool due = frame.index % every_n_frames_ == 0;
  if (!async_) {
    if (!due) {
      if (frame.detections && !frame.detections->empty()) {
        // A dataset labelled on more frames than the schedule runs: the maskfile plugin replays
        // only the scheduled ones. Said once, counted always (run.json).
        std::lock_guard<std::mutex> lock(mutex_);
        ++stats_.labelled_frames_skipped;
        if (!warned_skipped_labels_) {
          warned_skipped_labels_ = true;
          logWarning("frame ", frame.index,
                     " carries detections from the source, but the detector runs only on every ",
                     every_n_frames_,
                     "th frame (detector.every_n_frames), so the maskfile plugin skips this one; "
                     "set detector.every_n_frames=1 to replay every labelled frame");
        }
      }
      return std::nullopt;
    }
    // Run on the caller's frame without copying: a const view through a temporary slot would
    // copy the images, so the slot only carries the small fields.
    Slot view;
    view.frame.index = frame.index;
    view.frame.timestamp = frame.timestamp;
    view.frame.timestamp_text = frame.timestamp_text;
    view.frame.depth = frame.depth;  // cv::Mat headers share the pixels
    view.frame.color = frame.color;
    view.has_background_association = background_association && !background_association->empty();
    if (view.has_background_association) view.background_association = *background_association;
    view.has_residual = residual && !residual->empty();
    if (view.has_residual) view.residual = *residual;
    view.T_world_camera = T_world_camera;
    if (objects) view.objects = *objects;
    DetectionBatch batch;
    runDetector(view, &batch);
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.results_delivered;
    return batch;
  }

  std::unique_lock<std::mutex> lock(mutex_);
  std::optional<DetectionBatch> result = takeReady(frame.index);
  if (!due) return result;
  if (busy_) {
    ++stats_.dropped_frames;
    return result;
  }
  lock.unlock();
  // The detector thread is idle and only starts once busy_ is set: slot_ is ours.
  slot_.frame.index = frame.index;
  slot_.frame.timestamp = frame.timestamp;
  slot_.frame.timestamp_text = frame.timestamp_text;
  slot_.frame.rgb_timestamp = frame.rgb_timestamp;
  copyInto(frame.depth, &slot_.frame.depth);
  copyInto(frame.color, &slot_.frame.color);
  slot_.has_background_association = background_association && !background_association->empty();
  if (slot_.has_background_association) {
    copyInto(*background_association, &slot_.background_association);
  }
  slot_.has_residual = residual && !residual->empty();
  if (slot_.has_residual) copyInto(*residual, &slot_.residual);
  slot_.T_world_camera = T_world_camera;
  if (objects) {
    slot_.objects.assign(objects->begin(), objects->end());
  } else {
    slot_.objects.clear();
  }
  lock.lock();
  busy_ = true;
  lock.unlock();
  wake_.notify_one();
  return result;
}

std::optional<DetectionBatch> DetectorScheduler::finish() {
  if (!enabled() || !async_) return std::nullopt;
  std::unique_lock<std::mutex> lock(mutex_);
  idle_.wait(lock, [this] { return !busy_; });
  const int64_t index = has_ready_ ? ready_.frame_index : 0;
  return takeReady(index);
}

void DetectorScheduler::waitIdle() {
  if (!enabled() || !async_) return;
  std::unique_lock<std::mutex> lock(mutex_);
  idle_.wait(lock, [this] { return !busy_; });
}

bool DetectorScheduler::busy() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return busy_;
}

DetectorStats DetectorScheduler::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  DetectorStats s = stats_;
  if (!detector_ms_.empty()) {
    std::vector<double> ms = detector_ms_;
    const size_t mid = ms.size() / 2;
    std::nth_element(ms.begin(), ms.begin() + static_cast<std::ptrdiff_t>(mid), ms.end());
    s.detector_ms_median = ms[mid];
    if (ms.size() % 2 == 0) {
      const double lower =
          *std::max_element(ms.begin(), ms.begin() + static_cast<std::ptrdiff_t>(mid));
      s.detector_ms_median = 0.5 * (s.detector_ms_median + lower);
    }
    s.detector_ms_max = *std::max_element(detector_ms_.begin(), detector_ms_.end());
  }
  return s;
}

}  // namespace emf::pipeline
