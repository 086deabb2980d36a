// `emf synth <preset> --out DIR`: renders a synthetic sequence and writes it as a TUM folder
// with exact ground truth (camera, objects) and simulated detections.
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>

#include "cli/arg_parser.h"
#include "cli/commands.h"
#include "common/error.h"
#include "emf/emf.h"
#include "io/tum_writer.h"
#include "synth/presets.h"
#include "synth/synth_source.h"

namespace emf::cli {
namespace {
namespace fs = std::filesystem;

/// Parses an integer flag value; false (after printing a usage error) when malformed.
bool parseFlag(const ArgParser& p, const std::string& name, const std::string& text, long long lo,
               long long hi, long long* value) {
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (text.empty() || errno != 0 || *end != '\0' || v < lo || v > hi) {
    std::fprintf(stderr, "emf synth: --%s %s: expected an integer in [%lld, %lld]\n\n%s",
                 name.c_str(), text.c_str(), lo, hi, p.usage().c_str());
    return false;
  }
  *value = v;
  return true;
}

std::string presetList() {
  std::string s;
  for (const auto& n : synth::presetNames()) s += (s.empty() ? "" : ", ") + n;
  return s;
}

std::string joinNames(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

std::string partList() {
  std::string s;
  for (const auto& n : synth::noisePartNames()) s += (s.empty() ? "" : ", ") + n;
  return s;
}

}  // namespace

int cmdSynth(const std::vector<std::string>& args) {
  std::string preset, out, frames, seed, width, height, det_every, threads, noise_without;
  std::string movers, still, camera, motions;
  bool no_noise = false, force = false;
  ArgParser p("synth",
              "Renders a synthetic dynamic scene and writes it as a TUM RGB-D folder: rgb/, "
              "depth/ (uint16, 5000 per metre), rgb.txt, depth.txt, associations.txt, "
              "groundtruth.txt, calibration.txt, objects/gt-object-<k>-{camera,world}.txt and "
              "simulated detections in masks/ (see the folder's README.md). Presets: " +
                  presetList() + "; 'random' generates a different scene for every --seed.");
  p.positional("preset", &preset, "scene preset (" + presetList() + ") or random");
  p.option("out", &out, "DIR", "output folder (created; must be empty unless --force)");
  p.option("frames", &frames, "N", "number of frames (default: the preset's)");
  p.option("seed", &seed, "S", "seed of depth/colour noise and detections (default 1)");
  p.option("width", &width, "W", "image width in pixels (default 640)");
  p.option("height", &height, "H", "image height in pixels (default 480)");
  p.option("det-every", &det_every, "N",
           "run the simulated detector every N frames (default "
           "30, 0 = never)");
  p.option("threads", &threads, "N", "rendering threads (default: all cores)");
  p.option("movers", &movers, "N", "random only: moving objects, 1-4 (default: from the seed)");
  p.option("still", &still, "N",
           "random only: still detected objects, 0-4 (default: from the seed, 0-3)");
  p.option("camera", &camera, "NAME",
           "random only: camera family, " + joinNames(synth::cameraFamilyNames()) +
               " (default: from the seed)");
  p.option("motions", &motions, "LIST",
           "random only: motion families the movers are drawn from, comma-separated: " +
               joinNames(synth::motionFamilyNames()) + " (default: all)");
  p.flag("no-noise", &no_noise, "exact depth and colour (no sensor noise)");
  p.option("noise-without", &noise_without, "LIST",
           "switch these parts of the depth noise model off (comma-separated: " + partList() +
               "); the others stay on");
  p.flag("force", &force,
         "write into a non-empty folder (replaces rgb/, depth/, masks/, "
         "objects/ there)");
  if (auto code = p.parse(args)) return *code;
  if (out.empty()) {
    std::fprintf(stderr, "emf synth: --out DIR is required\n\n%s", p.usage().c_str());
    return kExitUsage;
  }
  const auto names = synth::presetNames();
  const bool random = preset == "random";
  if (!random && std::find(names.begin(), names.end(), preset) == names.end()) {
    std::fprintf(stderr,
                 "emf synth: unknown preset '%s': valid presets are %s, and random (a generated "
                 "scene per --seed)\n",
                 preset.c_str(), presetList().c_str());
    return kExitUsage;
  }
  if (!random && !(movers.empty() && still.empty() && camera.empty() && motions.empty())) {
    std::fprintf(stderr,
                 "emf synth: --movers, --still, --camera and --motions are for the generated "
                 "scenes only (emf synth random ...)\n");
    return kExitUsage;
  }

  synth::SynthOptions o;
  o.preset = preset;
  long long v = 0;
  if (!frames.empty()) {
    if (!parseFlag(p, "frames", frames, 1, 10000000, &v)) return kExitUsage;
    o.frames = static_cast<int>(v);
  }
  if (!seed.empty()) {
    if (!parseFlag(p, "seed", seed, 0, 9223372036854775807LL, &v)) return kExitUsage;
    o.seed = static_cast<uint64_t>(v);
  }
  if (!width.empty()) {
    if (!parseFlag(p, "width", width, 8, 8192, &v)) return kExitUsage;
    o.width = static_cast<int>(v);
  }
  if (!height.empty()) {
    if (!parseFlag(p, "height", height, 8, 8192, &v)) return kExitUsage;
    o.height = static_cast<int>(v);
  }
  if (!det_every.empty()) {
    if (!parseFlag(p, "det-every", det_every, 0, 1000000, &v)) return kExitUsage;
    o.detector.every_n_frames = static_cast<int>(v);
  }
  if (!threads.empty()) {
    if (!parseFlag(p, "threads", threads, 0, 64, &v)) return kExitUsage;
    o.threads = static_cast<int>(v);
  }
  if (!movers.empty()) {
    if (!parseFlag(p, "movers", movers, 1, 4, &v)) return kExitUsage;
    o.random.movers = static_cast<int>(v);
  }
  if (!still.empty()) {
    if (!parseFlag(p, "still", still, 0, 4, &v)) return kExitUsage;
    o.random.still = static_cast<int>(v);
  }
  if (!camera.empty()) {
    const auto& cams = synth::cameraFamilyNames();
    if (std::find(cams.begin(), cams.end(), camera) == cams.end()) {
      std::fprintf(stderr, "emf synth: --camera %s: valid camera families are %s\n", camera.c_str(),
                   joinNames(cams).c_str());
      return kExitUsage;
    }
    o.random.camera = camera;
  }
  if (!motions.empty()) {
    std::stringstream list(motions);
    std::string m;
    const auto& fams = synth::motionFamilyNames();
    while (std::getline(list, m, ',')) {
      if (std::find(fams.begin(), fams.end(), m) == fams.end()) {
        std::fprintf(stderr, "emf synth: --motions %s: unknown family '%s': valid ones are %s\n",
                     motions.c_str(), m.c_str(), joinNames(fams).c_str());
        return kExitUsage;
      }
      o.random.motions.push_back(m);
    }
  }
  o.noise = !no_noise;
  if (!noise_without.empty()) {
    if (no_noise) {
      std::fprintf(stderr,
                   "emf synth: --noise-without and --no-noise exclude each other (--no-noise "
                   "already switches every part off)\n");
      return kExitUsage;
    }
    std::stringstream list(noise_without);
    std::string part;
    while (std::getline(list, part, ',')) {
      if (!synth::disableNoisePart(part, &o.depth_noise)) {
        std::fprintf(stderr,
                     "emf synth: --noise-without %s: unknown part '%s': valid parts are %s\n",
                     noise_without.c_str(), part.c_str(), partList().c_str());
        return kExitUsage;
      }
    }
  }

  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec)) {
    throw IoError("--out " + out + " exists and is not a folder: choose another path");
  }
  if (fs::is_directory(out, ec) && !fs::is_empty(out, ec)) {
    if (!force) {
      throw IoError("--out " + out +
                    " is not empty: choose an empty or new folder, or pass --force to replace "
                    "the sequence there");
    }
    for (const char* sub : {"rgb", "depth", "masks", "objects"}) {
      fs::remove_all(fs::path(out) / sub, ec);
      if (ec)
        throw IoError("cannot remove " + (fs::path(out) / sub).string() + ": " + ec.message());
    }
  }

  synth::SynthSource source(o);
  std::string command =
      "emf synth " + preset + " --frames " + std::to_string(source.size()) + " --seed " +
      std::to_string(o.seed) + " --width " + std::to_string(o.width) + " --height " +
      std::to_string(o.height) + " --det-every " + std::to_string(o.detector.every_n_frames) +
      (o.noise ? "" : " --no-noise") +
      (noise_without.empty() ? "" : " --noise-without " + noise_without) +
      (movers.empty() ? "" : " --movers " + movers) + (still.empty() ? "" : " --still " + still) +
      (camera.empty() ? "" : " --camera " + camera) +
      (motions.empty() ? "" : " --motions " + motions);
  const synth::DetectorSimOptions& det = source.detector();
  io::TumWriterOptions wo;
  wo.readme_about =
      "Synthetic sequence `" + preset + "` made by emf " + std::to_string(EMF_VERSION_MAJOR) + "." +
      std::to_string(EMF_VERSION_MINOR) + "." + std::to_string(EMF_VERSION_PATCH) +
      " with\n\n    " + command + "\n\n" + source.scene().description + "\n\nSeed " +
      std::to_string(o.seed) +
      (random ? " chose the scene (room, furniture, objects, motions, camera) and drives the "
                "sensor and detector simulation. "
              : " drives the sensor and detector simulation only (geometry and motion are the "
                "same for every seed). ") +
      (o.noise ? "Depth has Kinect-like noise: axial sigma 0.0012 + 0.0019 (z - 0.4)^2 m "
                 "(plus an incidence-angle term), 1/8 px disparity quantisation (f 525 px, "
                 "baseline 0.075 m), dropped and jittered pixels at depth discontinuities, "
                 "projector shadows, range 0.4-4.5 m and 0.2 % random dropouts; colour has "
                 "uniform noise of 2 grey levels standard deviation."
               : "Depth and colour are exact (no sensor noise).") +
      (noise_without.empty() ? ""
                             : " Parts of the depth noise switched off: " + noise_without + ".") +
      (det.every_n_frames > 0
           ? " The simulated detector ran every " + std::to_string(det.every_n_frames) +
                 " frames (frames 0, " + std::to_string(det.every_n_frames) +
                 ", ...): masks with boundaries moved by up to " +
                 std::to_string(det.max_boundary_px) + " px and shifted by up to " +
                 std::to_string(det.max_shift_px) + " px (at 640 px), " +
                 std::to_string(static_cast<int>(std::lround(100 * det.miss_rate))) +
                 " % of visible objects missed, a false positive on " +
                 std::to_string(static_cast<int>(std::lround(100 * det.false_positive_rate))) +
                 " % of detection frames, classes confused " +
                 std::to_string(static_cast<int>(std::lround(100 * det.confusion_rate))) +
                 " %, gross spills " +
                 std::to_string(static_cast<int>(std::lround(100 * det.spill_rate))) +
                 " %, partial masks " +
                 std::to_string(static_cast<int>(std::lround(100 * det.partial_rate))) +
                 " %, results " + std::to_string(det.late_frames) +
                 " frame(s) late; scores in [0.5, 1], shuffled ids."
           : " No detections were simulated.") +
      "\n\nObject ids: " +
      [&] {
        std::string s;
        for (const auto& obj : source.scene().objects) {
          s += (s.empty() ? "" : ", ") + std::to_string(obj.id) + " = " + obj.class_name +
               (obj.motion.empty() ? "" : " (" + obj.motion + ")");
        }
        return s.empty() ? std::string("none (static scene)") : s;
      }() +
      ".";
  io::TumWriter writer(out, source.intrinsics(), wo);

  const auto t0 = std::chrono::steady_clock::now();
  const int64_t n = source.size();
  const int64_t step = std::max<int64_t>(1, n / 10);
  core::Frame frame;
  while (source.next(frame)) {
    writer.write(frame);
    const int64_t done = frame.index + 1;
    if (done % step == 0 || done == n) {
      std::fprintf(stderr, "emf synth: %s: %lld/%lld frames\n", preset.c_str(),
                   static_cast<long long>(done), static_cast<long long>(n));
    }
  }
  writer.finish();
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("wrote %lld frames of '%s' (%dx%d, seed %llu) to %s in %.1f s (%.1f ms/frame)\n",
              static_cast<long long>(n), preset.c_str(), o.width, o.height,
              static_cast<unsigned long long>(o.seed), out.c_str(), s, 1000.0 * s / n);
  return kExitOk;
}

}  // namespace emf::cli
