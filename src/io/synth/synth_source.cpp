#include "io/synth/synth_source.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <utility>

#include "common/error.h"
#include "io/synth/parallel.h"
#include "io/synth/presets.h"
#include "io/synth/rng.h"

namespace emf::io::synth {
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

}  // namespace

const std::vector<std::string>& synthQueryKeys() {
  static const std::vector<std::string> kKeys = {"frames",    "seed",  "width",  "height",
                                                 "det_every", "noise", "threads"};
  return kKeys;
}

SynthOptions synthOptionsFromQuery(const std::string& preset,
                                   const std::map<std::string, std::string>& query,
                                   const SourceOptions& source) {
  const auto names = presetNames();
  if (std::find(names.begin(), names.end(), preset) == names.end()) {
    throw IoError("synth: unknown preset '" + preset + "': valid presets are " + joined(names));
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
    } else {
      throw IoError("synth:" + preset + ": unknown query parameter '" + key + "': valid ones are " +
                    joined(synthQueryKeys()));
    }
  }
  if (source.fx > 0 || source.fy > 0 || source.cx > 0 || source.cy > 0) {
    Intrinsics k = defaultIntrinsics(o.width, o.height);
    if (source.fx > 0) k.fx = source.fx;
    if (source.fy > 0) k.fy = source.fy;
    if (source.cx > 0) k.cx = source.cx;
    if (source.cy > 0) k.cy = source.cy;
    o.intrinsics = k;
  }
  if (source.max_frames > 0) {
    const int preset_frames = o.frames > 0 ? o.frames : makePreset(preset).default_frames;
    o.frames = std::min(preset_frames, source.max_frames);
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

SynthSource::SynthSource(const SynthOptions& options)
    : SynthSource(options, makePreset(options.preset)) {}

SynthSource::SynthSource(const SynthOptions& options, Scene scene)
    : options_(options),
      scene_(std::move(scene)),
      renderer_(renderOptions(options)),
      noise_(options.depth_noise) {
  frames_ = options.frames > 0 ? options.frames : scene_.default_frames;
  for (const auto& obj : scene_.objects) classes_[obj.id] = obj.class_name;
}

bool SynthSource::next(Frame& frame) {
  if (next_index_ >= frames_) return false;
  renderFrame(next_index_++, &frame);
  return true;
}

std::string SynthSource::describe() const {
  char text[256];
  std::snprintf(
      text, sizeof(text),
      "synthetic scene '%s' (%lld frames, %dx%d, seed %llu, noise %s, detections %s)",
      scene_.name.c_str(), static_cast<long long>(frames_), options_.width, options_.height,
      static_cast<unsigned long long>(options_.seed), options_.noise ? "on" : "off",
      options_.detector.every_n_frames > 0
          ? ("every " + std::to_string(options_.detector.every_n_frames) + " frames").c_str()
          : "off");
  return text;
}

void SynthSource::renderFrame(int64_t index, Frame* frame) const {
  const double t = scene_.timeOf(index);
  const Eigen::Isometry3d T_world_camera = scene_.camera.pose(t);
  std::vector<Eigen::Isometry3d> T_world_objects;
  for (const auto& obj : scene_.objects) T_world_objects.push_back(obj.trajectory.pose(t));
  RenderOutput r;
  renderer_.render(scene_, T_world_camera, T_world_objects, &r);

  *frame = Frame();
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
  if (isDetectionFrame(index, options_.detector)) {
    frame->detections =
        simulateDetections(r.instance_ids, classes_, options_.seed, index, options_.detector);
  }
}

std::unique_ptr<FrameSource> openSynthSource(const std::string& preset,
                                             const std::map<std::string, std::string>& query,
                                             const SourceOptions& options) {
  return std::make_unique<SynthSource>(synthOptionsFromQuery(preset, query, options));
}

}  // namespace emf::io::synth
