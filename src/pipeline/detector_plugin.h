// Host side of the detector plugin ABI (include/emf/emf_detector.h): finds a plugin by name on
// the search path or by path, loads it with dlopen, checks the entry symbol, ABI version and
// struct sizes, and validates every result. A plugin that returns garbage never takes the SLAM
// down: bad detections are dropped with a reason, a failed call yields no detections.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "common/error.h"
#include "core/frame.h"
#include "emf/emf_detector.h"

namespace emf::pipeline {

/// A plugin could not be found, loaded or created (message says which file and what to do).
/// status() is the C API's code for it: EMF_ERROR_NOT_FOUND (no such plugin),
/// EMF_ERROR_VERSION_MISMATCH (ABI), EMF_ERROR_IO (not a loadable plugin), or the plugin's own
/// error from create() (EMF_ERROR_CONFIG when it gave none).
class PluginError : public Error {
 public:
  explicit PluginError(const std::string& message, emf_status status = EMF_ERROR_CONFIG)
      : Error(message), status_(status) {}
  emf_status status() const { return status_; }

 private:
  emf_status status_;
};

/// The outcome of one detect() call.
struct DetectorOutput {
  std::vector<core::Detection> detections;  // valid detections, ids 1..n in plugin order
  std::vector<std::string> rejected;        // one message per dropped detection
  std::string error;                        // non-empty when the call failed as a whole
  /// The detector reports only what the SLAM does not explain yet
  /// (EMF_DETECTOR_FLAG_NEW_OBJECTS_ONLY): unmatched objects get no NonEx from this call.
  bool new_objects_only = false;
};

/// The shared object for `name_or_path`: a path (contains '/' or ends in .so) is used as is;
/// a name is looked up as libemf_detector_<name>.so, then <name>.so, in each folder of
/// `search_path`. Throws PluginError listing the folders searched.
std::string resolvePluginPath(const std::string& name_or_path,
                              const std::vector<std::string>& search_path);

class DetectorPlugin {
 public:
  /// Loads and creates a detector. `config` is passed to the plugin's create().
  static std::unique_ptr<DetectorPlugin> load(const std::string& name_or_path,
                                              const std::vector<std::string>& search_path,
                                              const std::string& config,
                                              const std::string& source_uri,
                                              const core::Intrinsics& intrinsics);
  ~DetectorPlugin();
  DetectorPlugin(const DetectorPlugin&) = delete;
  DetectorPlugin& operator=(const DetectorPlugin&) = delete;

  /// Runs the plugin on `frame` (depth CV_32F metres, colour BGR). Optional SLAM feedback
  /// images (CV_32F, depth size) may be null. Never throws for plugin misbehaviour.
  DetectorOutput detect(const core::Frame& frame, const cv::Mat* background_association = nullptr,
                        const cv::Mat* residual = nullptr);

  const std::string& name() const { return name_; }
  /// The plugin's EMF_DETECTOR_FLAG_NEW_OBJECTS_ONLY (false for plugins built before the
  /// flags field existed).
  bool newObjectsOnly() const;
  /// The plugin's EMF_DETECTOR_FLAG_READS_FEEDBACK (true for plugins built before the flags
  /// field existed: they may read it).
  bool readsFeedback() const;
  const std::string& path() const { return path_; }
  /// Whether detect() logs each failure and dropped detection as a warning (default true). The
  /// DetectorScheduler turns it off and logs once per kind of problem instead.
  void setLogProblems(bool log_problems) { log_problems_ = log_problems; }

 private:
  DetectorPlugin() = default;
  void* handle_ = nullptr;
  const emf_detector_api* api_ = nullptr;
  emf_detector* instance_ = nullptr;
  std::string name_, path_;
  core::Intrinsics intrinsics_;
  bool log_problems_ = true;
};

}  // namespace emf::pipeline
