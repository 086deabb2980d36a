#include "synth/synth_source.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <utility>

#include "common/error.h"
#include "synth/parallel.h"
#include "synth/presets.h"
#include "synth/rng.h"

namespace emf::synth {
namespace {

constexpr uint64_t kColorStream = 0x636f6c6f72ull;  // "color"

std::string joined(const std::vector<std::string>& items) {
  std::string s;
  for (const auto& i : items) s += (s.empty() ? "" : ", ") + i;
  return s;
}

std::string where(const std::string& preset, const std::string& key, const std::string& value) {
  return "synth:" + preset + ": query parameter " + key + "=" + value;
}

long long parseInteger(const std::string& preset, const std::string& key, const std::string& value,
                       long long lo, long long hi) {
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(value.c_str(), &end, 10);
  if (value.empty() || errno != 0 || *end != '\0') {
    throw IoError(where(preset, key, value) + " is not an integer");
  }
  if (v < lo || v > hi) {
    throw IoError(where(preset, key, value) + " is out of range [" + std::to_string(lo) + ", " +
                  std::to_string(hi) + "]");
  }
  return v;
}

uint64_t parseSeed(const std::string& preset, const std::string& value) {
  errno = 0;
  char* end = nullptr;
  const unsigned long long v = std::strtoull(value.c_str(), &end, 10);
  if (value.empty() || value[0] == '-' || errno != 0 || *end != '\0') {
    throw IoError(where(preset, "seed", value) + " is not an unsigned 64-bit integer");
  }
  return v;
}

bool parseBool(const std::string& preset, const std::string& key, const std::string& value) {
  if (value == "1" || value == "true" || value == "on" || value == "yes") return true;
  if (value == "0" || value == "false" || value == "off" || value == "no") return false;
  throw IoError(where(preset, key, value) + " is not a boolean: use 0/1, true/false or on/off");
}

double parseReal(const std::string& preset, const std::string& key, const std::string& value,
                 double lo, double hi) {
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(value.c_str(), &end);
  if (value.empty() || errno != 0 || *end != '\0' || !std::isfinite(v)) {
    throw IoError(where(preset, key, value) + " is not a number");
  }
  if (v < lo || v > hi) {
    throw IoError(where(preset, key, value) + " is out of range [" + std::to_string(lo) + ", " +
                  std::to_string(hi) + "]");
  }
  return v;
}

const std::vector<std::string>& randomOnlyKeys() {
  static const std::vector<std::string> kKeys = {"movers", "still", "camera", "motions"};
  return kKeys;
}

}  // namespace

void DetectorOverrides::applyTo(DetectorSimOptions* d) const {
  if (miss_rate) d->miss_rate = *miss_rate;
  if (false_positive_rate) d->false_positive_rate = *false_positive_rate;
  if (confusion_rate) d->confusion_rate = *confusion_rate;
  if (spill_rate) d->spill_rate = *spill_rate;
  if (partial_rate) d->partial_rate = *partial_rate;
  if (late_frames) d->late_frames = *late_frames;
}

const std::vector<std::string>& synthQueryKeys() {
  static const std::vector<std::string> kKeys = {
      "frames",   "seed",     "width",  "height",        "det_every", "noise",
      "threads",  "det_miss", "det_fp", "det_confusion", "det_spill", "det_partial",
      "det_late", "movers",   "still",  "camera",        "motions"};
  return kKeys;
}

SynthOptions synthOptionsFromQuery(const std::string& preset,
                                   const std::map<std::string, std::string>& query,
                                   const core::SourceOptions& source) {
  const auto names = presetNames();
  if (preset != "random" && std::find(names.begin(), names.end(), preset) == names.end()) {
    throw IoError("synth: unknown preset '" + preset + "': valid presets are " + joined(names) +
                  ", and 'random' (the generated scenes, synth:random?seed=N)");
  }
  SynthOptions o;
  o.preset = preset;
  for (const auto& [key, value] : query) {
    if (key == "frames") {
      o.frames = static_cast<int>(parseInteger(preset, key, value, 1, 10000000));
    } else if (key == "seed") {
      o.seed = parseSeed(preset, value);
    } else if (key == "width") {
      o.width = static_cast<int>(parseInteger(preset, key, value, 8, 8192));
    } else if (key == "height") {
      o.height = static_cast<int>(parseInteger(preset, key, value, 8, 8192));
    } else if (key == "det_every") {
      o.detector.every_n_frames = static_cast<int>(parseInteger(preset, key, value, 0, 1000000));
    } else if (key == "noise") {
      o.noise = parseBool(preset, key, value);
    } else if (key == "threads") {
      o.threads = static_cast<int>(parseInteger(preset, key, value, 0, 64));
    } else if (key == "det_miss") {
      o.detector_overrides.miss_rate = parseReal(preset, key, value, 0.0, 1.0);
    } else if (key == "det_fp") {
      o.detector_overrides.false_positive_rate = parseReal(preset, key, value, 0.0, 1.0);
    } else if (key == "det_confusion") {
      o.detector_overrides.confusion_rate = parseReal(preset, key, value, 0.0, 1.0);
    } else if (key == "det_spill") {
      o.detector_overrides.spill_rate = parseReal(preset, key, value, 0.0, 1.0);
    } else if (key == "det_partial") {
      o.detector_overrides.partial_rate = parseReal(preset, key, value, 0.0, 1.0);
    } else if (key == "det_late") {
      o.detector_overrides.late_frames = static_cast<int>(parseInteger(preset, key, value, 0, 30));
    } else if (std::find(randomOnlyKeys().begin(), randomOnlyKeys().end(), key) !=
               randomOnlyKeys().end()) {
      if (preset != "random") {
        throw IoError("synth:" + preset + ": query parameter '" + key +
                      "' is for the generated scenes only (synth:random?seed=N&" + key + "=...)");
      }
      if (key == "movers") {
        o.random.movers = static_cast<int>(parseInteger(preset, key, value, 1, 4));
      } else if (key == "still") {
        o.random.still = static_cast<int>(parseInteger(preset, key, value, 0, 4));
      } else if (key == "camera") {
        const auto& cams = cameraFamilyNames();
        if (std::find(cams.begin(), cams.end(), value) == cams.end()) {
          throw IoError(where(preset, key, value) + ": valid camera families are " + joined(cams));
        }
        o.random.camera = value;
      } else {
        o.random.motions.clear();
        std::string item;
        for (size_t i = 0; i <= value.size(); ++i) {
          if (i == value.size() || value[i] == ',') {
            const auto& fams = motionFamilyNames();
            if (std::find(fams.begin(), fams.end(), item) == fams.end()) {
              throw IoError(where(preset, key, value) + ": unknown motion family '" + item +
                            "': valid ones are " + joined(fams));
            }
            o.random.motions.push_back(item);
            item.clear();
          } else {
            item += value[i];
          }
        }
      }
    } else {
      throw IoError("synth:" + preset + ": unknown query parameter '" + key + "': valid ones are " +
                    joined(synthQueryKeys()));
    }
  }
  if (source.fx > 0 || source.fy > 0 || source.cx > 0 || source.cy > 0) {
    core::Intrinsics k = defaultIntrinsics(o.width, o.height);
    if (source.fx > 0) k.fx = source.fx;
    if (source.fy > 0) k.fy = source.fy;
    if (source.cx > 0) k.cx = source.cx;
    if (source.cy > 0) k.cy = source.cy;
    o.intrinsics = k;
  }
  if (source.max_frames > 0) {
    const int preset_frames = o.frames > 0         ? o.frames
                              : preset == "random" ? o.random.frames
                                                   : makePreset(preset).default_frames;
    o.frames = std::min(preset_frames, source.max_frames);
  }
  if (preset == "random" && o.random.camera == "orbit" && o.random.motions.size() == 1 &&
      o.random.motions[0] == "pass") {
    throw IoError(
        "synth:random: motions=pass needs camera=sweep or camera=xyz (an orbiting "
        "camera has no side to enter from)");
  }
  return o;
}

namespace {
RenderOptions renderOptions(const SynthOptions& o) {
  RenderOptions r;
  r.width = o.width;
  r.height = o.height;
  r.intrinsics = o.intrinsics;
  r.threads = o.threads;
  return r;
}
}  // namespace

Scene makeScene(const SynthOptions& options, DetectorSimOptions* detector) {
  if (options.preset != "random") return makePreset(options.preset);
  RandomSceneOptions r = options.random;
  if (options.frames > 0) r.frames = std::max(30, options.frames);
  RandomScene generated = makeRandomScene(options.seed, r);
  const int every = detector->every_n_frames;
  *detector = generated.detector;
  detector->every_n_frames = every;
  return std::move(generated.scene);
}

SynthSource::SynthSource(const SynthOptions& options)
    : options_(options), renderer_(renderOptions(options)), noise_(options.depth_noise) {
  detector_ = options.detector;
  scene_ = makeScene(options, &detector_);
  options.detector_overrides.applyTo(&detector_);
  frames_ = options.frames > 0 ? options.frames : scene_.default_frames;
  for (const auto& obj : scene_.objects) classes_[obj.id] = obj.class_name;
}

SynthSource::SynthSource(const SynthOptions& options, Scene scene)
    : options_(options),
      scene_(std::move(scene)),
      renderer_(renderOptions(options)),
      noise_(options.depth_noise),
      detector_(options.detector) {
  options.detector_overrides.applyTo(&detector_);
  frames_ = options.frames > 0 ? options.frames : scene_.default_frames;
  for (const auto& obj : scene_.objects) classes_[obj.id] = obj.class_name;
}

bool SynthSource::next(core::Frame& frame) {
  if (next_index_ >= frames_) return false;
  renderFrame(next_index_++, &frame);
  return true;
}

std::string SynthSource::describe() const {
  char text[256];
  std::snprintf(text, sizeof(text),
                "synthetic scene '%s' (%lld frames, %dx%d, seed %llu, noise %s, detections %s)",
                scene_.name.c_str(), static_cast<long long>(frames_), options_.width,
                options_.height, static_cast<unsigned long long>(options_.seed),
                options_.noise ? "on" : "off",
                detector_.every_n_frames > 0
                    ? ("every " + std::to_string(detector_.every_n_frames) + " frames").c_str()
                    : "off");
  return text;
}

void SynthSource::renderFrame(int64_t index, core::Frame* frame) const {
  const double t = scene_.timeOf(index);
  const Eigen::Isometry3d T_world_camera = scene_.camera.pose(t);
  std::vector<Eigen::Isometry3d> T_world_objects;
  for (const auto& obj : scene_.objects) T_world_objects.push_back(obj.trajectory.pose(t));
  RenderOutput r;
  renderer_.render(scene_, T_world_camera, T_world_objects, &r);

  *frame = core::Frame();
  frame->index = index;
  frame->timestamp = t;
  char ts[64];
  std::snprintf(ts, sizeof(ts), "%.6f", t);
  frame->timestamp_text = ts;
  frame->rgb_timestamp = t;
  frame->T_world_camera_gt = T_world_camera;
  for (size_t k = 0; k < scene_.objects.size(); ++k) {
    frame->T_world_object_gt[scene_.objects[k].id] = T_world_objects[k];
  }
  frame->instance_ids = r.instance_ids;
  const int threads = resolveThreads(options_.threads);
  if (options_.noise) {
    noise_.apply(r.depth, r.cos_incidence, renderer_.intrinsics().fx, options_.seed, index,
                 &frame->depth, threads);
    // Uniform noise per channel: half-width sqrt(3) sigma gives standard deviation sigma.
    const double half_width = std::sqrt(3.0) * options_.color_noise_sigma;
    if (half_width > 0) {
      parallelFor(r.color.rows, threads, [&](int vb, int ve) {
        for (int v = vb; v < ve; ++v) {
          Rng rng(streamSeed(options_.seed, static_cast<uint64_t>(index), static_cast<uint64_t>(v),
                             kColorStream));
          auto* row = r.color.ptr<uint8_t>(v);
          for (int i = 0; i < r.color.cols; ++i) {
            uint64_t bits = rng.next();
            for (int c = 0; c < 3; ++c, bits >>= 16) {
              const double u = static_cast<double>(bits & 0xffff) / 65535.0;
              const double value = row[3 * i + c] + (2.0 * u - 1.0) * half_width;
              row[3 * i + c] = cv::saturate_cast<uint8_t>(value);
            }
          }
        }
      });
    }
  } else {
    frame->depth = r.depth;
  }
  frame->color = r.color;
  if (isDetectionFrame(index, detector_)) {
    if (detector_.late_frames == 0) {
      frame->detections =
          simulateDetections(r.instance_ids, classes_, options_.seed, index, detector_);
    } else if (index >= detector_.late_frames) {
      // A late result: the detector saw the frame late_frames ago.
      const double t_seen = scene_.timeOf(index - detector_.late_frames);
      std::vector<Eigen::Isometry3d> seen_objects;
      for (const auto& obj : scene_.objects) seen_objects.push_back(obj.trajectory.pose(t_seen));
      RenderOutput seen;
      renderer_.render(scene_, scene_.camera.pose(t_seen), seen_objects, &seen);
      frame->detections =
          simulateDetections(seen.instance_ids, classes_, options_.seed, index, detector_);
    }
  }
}

std::unique_ptr<core::FrameSource> openSynthSource(const std::string& preset,
                                                   const std::map<std::string, std::string>& query,
                                                   const core::SourceOptions& options) {
  return std::make_unique<SynthSource>(synthOptionsFromQuery(preset, query, options));
}

}  // namespace emf::synth
