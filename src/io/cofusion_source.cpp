#include "io/cofusion_source.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <map>
#include <opencv2/imgcodecs.hpp>

#include "common/error.h"
#include "common/log.h"
#include "io/depth_image.h"
#include "io/tum_source.h"

namespace emf::io {
namespace fs = std::filesystem;
namespace {

// Depths at or beyond this are renderer "no hit" values (Blender writes 1e10), not geometry.
constexpr float kMaxValidDepthM = 1000.f;

// Files `<prefix><digits><ext>` in `dir` by number (prefix empty = any non-digit prefix).
std::map<long, std::string> numberedFiles(const fs::path& dir, const std::string& prefix,
                                          const std::string& ext) {
  std::map<long, std::string> out;
  if (!fs::is_directory(dir)) return out;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.size() <= ext.size() || name.compare(name.size() - ext.size(), ext.size(), ext)) {
      continue;
    }
    const std::string stem = name.substr(0, name.size() - ext.size());
    size_t digits = stem.size();
    while (digits > 0 && std::isdigit(static_cast<unsigned char>(stem[digits - 1]))) --digits;
    if (digits == stem.size()) continue;
    if (!prefix.empty() && stem.substr(0, digits) != prefix) continue;
    const long number = std::strtol(stem.c_str() + digits, nullptr, 10);
    const auto [it, inserted] = out.emplace(number, entry.path().string());
    if (!inserted) {
      throw IoError("'" + entry.path().string() + "' and '" + it->second + "' both have number " +
                    std::to_string(number) + " (padded differently); remove one of them");
    }
  }
  return out;
}

std::string sizeText(cv::Size s) {
  return std::to_string(s.width) + "x" + std::to_string(s.height);
}

}  // namespace

CoFusionSource::CoFusionSource(const std::string& dir, const core::SourceOptions& options,
                               double fps)
    : dir_(dir), fps_(fps) {
  enableOpenExr();
  const fs::path root(dir);
  if (!fs::is_directory(root)) {
    throw IoError("Co-Fusion folder '" + dir + "' does not exist or is not a folder");
  }
  std::map<long, std::string> depth;
  for (const char* sub : {"", "depth_noise", "depth_original"}) {
    depth = numberedFiles(root / sub, "Depth", ".exr");
    if (!depth.empty()) break;
  }
  if (depth.empty()) {
    throw IoError("'" + dir +
                  "' is not a Co-Fusion folder: no Depth####.exr files in it or in "
                  "depth_noise/ or depth_original/");
  }
  auto color = numberedFiles(root, "Color", ".png");
  if (color.empty()) color = numberedFiles(root / "colour", "Color", ".png");
  const auto masks = numberedFiles(root / "masks_id", "", ".png");
  if (color.empty()) logWarning("Co-Fusion folder '", dir, "': no Color####.png, depth only");

  for (const auto& [number, depth_path] : depth) {
    Entry e{number, "", depth_path, ""};
    if (!color.empty()) {
      auto it = color.find(number);
      if (it == color.end()) {
        throw IoError("Co-Fusion folder '" + dir + "': '" + depth_path +
                      "' has no colour image with the same number (a Color*.png numbered " +
                      std::to_string(number) + ")");
      }
      e.color = it->second;
    }
    if (auto it = masks.find(number); it != masks.end()) e.mask = it->second;
    frames_.push_back(e);
  }
  if (options.max_frames > 0 && frames_.size() > static_cast<size_t>(options.max_frames)) {
    frames_.resize(static_cast<size_t>(options.max_frames));
  }
  // Timestamps follow the file numbers, so a gap in the numbering is a gap in time.
  const long span = frames_.back().number - frames_.front().number + 1;
  if (span > static_cast<long>(frames_.size())) {
    logWarning("Co-Fusion folder '", dir, "': ", span - static_cast<long>(frames_.size()),
               " frame number(s) between ", frames_.front().number, " and ", frames_.back().number,
               " have no depth file; the timestamps keep the gaps (number / fps)");
  }
  depth_size_ = readDepth(frames_[0].depth).size();
  intrinsics_ = resolveIntrinsics(options, (root / "calibration.txt").string(), depth_size_,
                                  "Co-Fusion folder '" + dir + "'");
}

cv::Mat CoFusionSource::readDepth(const std::string& path) const {
  const cv::Mat raw = readImageFile(path, cv::IMREAD_UNCHANGED, "depth EXR", "");
  if (raw.empty()) {
    const char* env = std::getenv("OPENCV_IO_ENABLE_OPENEXR");
    throw IoError("cannot decode depth EXR '" + path + "': the file is corrupt, or OpenCV's " +
                  "EXR codec is unavailable (OPENCV_IO_ENABLE_OPENEXR is '" +
                  (env ? env : "unset") +
                  "'; it must be 1 before the first image is read, and OpenCV must be built "
                  "with OpenEXR)");
  }
  if (raw.depth() != CV_32F) {
    throw IoError("depth EXR '" + path + "' is " + describeMatType(raw.type()) +
                  "; expected float depth in metres");
  }
  cv::Mat depth;
  if (raw.channels() == 1) {
    depth = raw;
  } else {
    cv::extractChannel(raw, depth, 0);
  }
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int y = 0; y < depth.rows; ++y) {
    float* row = depth.ptr<float>(y);
    for (int x = 0; x < depth.cols; ++x) {
      if (!(row[x] > 0.f && row[x] < kMaxValidDepthM)) row[x] = nan;
    }
  }
  return depth;
}

bool CoFusionSource::next(core::Frame& frame) {
  if (cursor_ >= frames_.size()) return false;
  const Entry& e = frames_[cursor_];
  core::Frame f;
  f.index = static_cast<int64_t>(cursor_);
  f.timestamp = f.rgb_timestamp = static_cast<double>(e.number - frames_.front().number) / fps_;
  char text[64];
  std::snprintf(text, sizeof(text), "%.6f", f.timestamp);
  f.timestamp_text = text;
  f.depth = readDepth(e.depth);
  if (f.depth.size() != depth_size_) {
    throw IoError("depth EXR '" + e.depth + "' is " + sizeText(f.depth.size()) +
                  " but the first frame's is " + sizeText(depth_size_) +
                  "; all frames must have the same size");
  }
  if (!e.color.empty()) {
    f.color = readColor(e.color, "Co-Fusion frame " + std::to_string(e.number));
    if (color_size_.area() == 0) color_size_ = f.color.size();
    if (f.color.size() != color_size_) {
      throw IoError("colour image '" + e.color + "' is " + sizeText(f.color.size()) +
                    " but the first frame's is " + sizeText(color_size_) +
                    "; all frames must have the same size");
    }
  }
  if (!e.mask.empty()) {
    const cv::Mat ids = readImageFile(e.mask, cv::IMREAD_UNCHANGED, "instance mask", "");
    if (ids.empty()) throw IoError("cannot decode instance mask '" + e.mask + "'");
    if (ids.type() != CV_8UC1 && ids.type() != CV_16UC1) {
      throw IoError("instance mask '" + e.mask + "' is " + describeMatType(ids.type()) +
                    "; expected an 8- or 16-bit single-channel id image (0 = background)");
    }
    if (ids.size() != depth_size_) {
      throw IoError("instance mask '" + e.mask + "' is " + sizeText(ids.size()) +
                    " but the depth images are " + sizeText(depth_size_));
    }
    ids.convertTo(f.instance_ids, CV_16U);
  }
  frame = std::move(f);
  ++cursor_;
  return true;
}

std::string CoFusionSource::describe() const {
  return "Co-Fusion folder " + dir_ + ", " + std::to_string(frames_.size()) + " frames " +
         sizeText(depth_size_);
}

}  // namespace emf::io
