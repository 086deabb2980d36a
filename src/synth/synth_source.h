// The synthetic world as a FrameSource: `synth:<preset>[?frames=N&seed=S&width=W&height=H&
// det_every=N&noise=0|1&threads=N&det_miss=P&det_fp=P&det_confusion=P&det_spill=P&
// det_partial=P&det_late=N]` and the generated family `synth:random?seed=S[&movers=N&still=N&
// camera=NAME&motions=A,B]` (random_scene.h). Frames carry exact ground truth
// (T_world_camera_gt, T_world_object_gt by object id, instance_ids) and, every det_every
// frames, simulated detections. Timestamps are index / 30 s, timestamp_text "%.6f".
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "core/frame_source.h"
#include "synth/depth_noise.h"
#include "synth/detector_sim.h"
#include "synth/random_scene.h"
#include "synth/renderer.h"
#include "synth/scene.h"

namespace emf::synth {

/// Detector imperfections set by the caller (query keys det_*) over the scene's own.
struct DetectorOverrides {
  std::optional<double> miss_rate, false_positive_rate, confusion_rate, spill_rate, partial_rate;
  std::optional<int> late_frames;
  void applyTo(DetectorSimOptions* d) const;
};

struct SynthOptions {
  /// A preset (presetNames()) or "random" (the generated family; the seed picks the scene).
  std::string preset = "room";
  /// Number of frames (0 = the preset's default).
  int frames = 0;
  /// Drives depth noise, colour noise and detections (not the geometry or motion).
  uint64_t seed = 1;
  int width = 640, height = 480;
  /// Pinhole camera override; when not valid(), defaultIntrinsics(width, height).
  core::Intrinsics intrinsics;
  /// false: exact depth and noise-free colour (the depth_noise / colour settings are ignored).
  bool noise = true;
  DepthNoiseOptions depth_noise;
  /// Colour sensor noise: uniform per channel with this standard deviation (grey levels).
  double color_noise_sigma = 2.0;
  /// The simulated detector (every_n_frames = 0: no detections). A generated scene brings its
  /// own imperfections: only every_n_frames is taken from here for it.
  DetectorSimOptions detector;
  DetectorOverrides detector_overrides;
  /// The generated scene's contents (preset "random"; frames is set from `frames`).
  RandomSceneOptions random;
  /// Rendering/noise threads (0 = hardware concurrency).
  int threads = 0;
};

/// Valid query keys of `synth:` URIs, in documentation order.
const std::vector<std::string>& synthQueryKeys();

/// SynthOptions for `synth:<preset>?<query>` on top of `source` (fx/fy/cx/cy > 0 override the
/// camera, max_frames > 0 caps the frame count). Throws IoError naming an unknown preset or
/// query key (listing the valid ones) or a malformed / out-of-range value.
SynthOptions synthOptionsFromQuery(const std::string& preset,
                                   const std::map<std::string, std::string>& query,
                                   const core::SourceOptions& source);

class SynthSource : public core::FrameSource {
 public:
  /// Throws IoError for an unknown preset, InvalidArgument for a bad size.
  explicit SynthSource(const SynthOptions& options);
  /// The caller's own scene instead of a preset (options.preset is ignored): tests and custom
  /// worlds. options.frames = 0 takes scene.default_frames.
  SynthSource(const SynthOptions& options, Scene scene);

  core::Intrinsics intrinsics() const override { return renderer_.intrinsics(); }
  bool next(core::Frame& frame) override;
  int64_t size() const override { return frames_; }
  std::string describe() const override;

  const Scene& scene() const { return scene_; }
  const SynthOptions& options() const { return options_; }
  /// The simulated detector's settings in force (the preset's or the generated scene's, with
  /// the overrides).
  const DetectorSimOptions& detector() const { return detector_; }
  /// Renders frame `index` (0-based) into *frame, independently of the read position.
  void renderFrame(int64_t index, core::Frame* frame) const;

 private:
  SynthOptions options_;
  Scene scene_;
  Renderer renderer_;
  DepthNoiseModel noise_;
  DetectorSimOptions detector_;
  std::map<int, std::string> classes_;
  int64_t frames_ = 0;
  int64_t next_index_ = 0;
};

/// The scene named by options.preset: a preset, or the generated scene of options.seed with
/// *detector set to its imperfections (a preset leaves *detector alone).
Scene makeScene(const SynthOptions& options, DetectorSimOptions* detector);

/// The entry the URI parser calls for `synth:<preset>?<query>`.
std::unique_ptr<core::FrameSource> openSynthSource(const std::string& preset,
                                                   const std::map<std::string, std::string>& query,
                                                   const core::SourceOptions& options);

}  // namespace emf::synth
