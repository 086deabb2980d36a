#include "io/tum_writer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "common/error.h"
#include "common/log.h"
#include "io/atomic_output.h"

namespace emf::io {
namespace fs = std::filesystem;
namespace {

std::string formatTime(double t) {
  char s[64];
  std::snprintf(s, sizeof(s), "%.6f", t);
  return s;
}

std::string frameName(const core::Frame& f) {
  return "frame " + std::to_string(f.index) + " (t=" + f.timestamp_text + ")";
}

const char* kListHeader =
    "# %s\n"
    "# file: written by emf (TumWriter)\n"
    "# timestamp filename\n";

std::string listHeader(const char* what) {
  char s[256];
  std::snprintf(s, sizeof(s), kListHeader, what);
  return s;
}

}  // namespace

std::string tumPoseLine(const std::string& timestamp_text, const Eigen::Isometry3d& T) {
  Eigen::Quaterniond q(T.linear());
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1.0;
  const Eigen::Vector3d t = T.translation();
  char s[256];
  std::snprintf(s, sizeof(s), "%s %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", timestamp_text.c_str(),
                t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
  return s;
}

std::string maskClassToken(const std::string& class_name) {
  std::string s = class_name.empty() ? std::string("unknown") : class_name;
  std::replace_if(
      s.begin(), s.end(), [](char c) { return c == ' ' || c == '\t' || c == '\n'; }, '_');
  return s;
}

TumWriter::TumWriter(const std::string& dir, const core::Intrinsics& intrinsics,
                     const TumWriterOptions& options)
    : dir_(dir), intrinsics_(intrinsics), options_(options) {
  if (!intrinsics.valid()) {
    throw IoError("TUM writer for " + dir + ": invalid intrinsics (fx, fy, width, height > 0)");
  }
  if (options.depth_scale <= 0) {
    throw IoError("TUM writer for " + dir + ": depth_scale must be > 0");
  }
  for (const char* sub : {"", "rgb", "depth", "objects", "masks"}) {
    std::error_code ec;
    fs::create_directories(fs::path(dir) / sub, ec);
    if (ec) {
      throw IoError("cannot create folder " + (fs::path(dir) / sub).string() + ": " + ec.message());
    }
  }
  rgb_list_ = listHeader("color images");
  depth_list_ = listHeader("depth maps");
  groundtruth_ =
      "# ground truth trajectory (T_world_camera)\n"
      "# file: written by emf (TumWriter)\n"
      "# timestamp tx ty tz qx qy qz qw\n";
}

void TumWriter::write(const core::Frame& frame) {
  if (finished_) throw IoError("TUM writer for " + dir_ + ": write() after finish()");
  const std::string name = frameName(frame);
  if (frame.depth.empty() || frame.depth.type() != CV_32F) {
    throw IoError("TUM writer for " + dir_ + ": " + name + " has no CV_32F depth image");
  }
  if (frame.depth.cols != intrinsics_.width || frame.depth.rows != intrinsics_.height) {
    throw IoError("TUM writer for " + dir_ + ": " + name + " depth is " +
                  std::to_string(frame.depth.cols) + "x" + std::to_string(frame.depth.rows) +
                  " but the calibration says " + std::to_string(intrinsics_.width) + "x" +
                  std::to_string(intrinsics_.height));
  }
  if (frame.color.empty() || frame.color.type() != CV_8UC3) {
    throw IoError("TUM writer for " + dir_ + ": " + name + " has no CV_8UC3 colour image");
  }
  const std::string t_depth =
      frame.timestamp_text.empty() ? formatTime(frame.timestamp) : frame.timestamp_text;
  const std::string t_rgb =
      frame.rgb_timestamp == frame.timestamp ? t_depth : formatTime(frame.rgb_timestamp);
  const std::vector<int> png = {cv::IMWRITE_PNG_COMPRESSION, options_.png_compression};

  cv::Mat depth16(frame.depth.size(), CV_16U);
  for (int v = 0; v < frame.depth.rows; ++v) {
    const float* in = frame.depth.ptr<float>(v);
    uint16_t* out = depth16.ptr<uint16_t>(v);
    for (int u = 0; u < frame.depth.cols; ++u) {
      const double units = std::isfinite(in[u]) ? std::round(in[u] * options_.depth_scale) : 0.0;
      if (units > 65535.0) ++unrepresentable_depth_;
      out[u] = (units >= 1.0 && units <= 65535.0) ? static_cast<uint16_t>(units) : 0;
    }
  }
  const std::string rgb_file = "rgb/" + t_rgb + ".png";
  const std::string depth_file = "depth/" + t_depth + ".png";
  writeImageAtomically((fs::path(dir_) / rgb_file).string(), frame.color, png);
  writeImageAtomically((fs::path(dir_) / depth_file).string(), depth16, png);
  rgb_list_ += t_rgb + " " + rgb_file + "\n";
  depth_list_ += t_depth + " " + depth_file + "\n";
  associations_ += t_rgb + " " + rgb_file + " " + t_depth + " " + depth_file + "\n";

  if (frame.T_world_camera_gt) groundtruth_ += tumPoseLine(t_depth, *frame.T_world_camera_gt);

  std::vector<int> counts;
  if (!frame.instance_ids.empty()) {
    if (frame.instance_ids.type() != CV_16U) {
      throw IoError("TUM writer for " + dir_ + ": " + name + " instance ids are not CV_16U");
    }
    counts.assign(65536, 0);
    for (int v = 0; v < frame.instance_ids.rows; ++v) {
      const uint16_t* row = frame.instance_ids.ptr<uint16_t>(v);
      for (int u = 0; u < frame.instance_ids.cols; ++u) ++counts[row[u]];
    }
  }
  const double min_pixels = std::max(
      1.0, std::round(options_.min_visible_fraction * intrinsics_.width * intrinsics_.height));
  for (const auto& [id, T_world_object] : frame.T_world_object_gt) {
    object_world_[id] += tumPoseLine(t_depth, T_world_object);
    const bool visible = counts.empty() || (id >= 0 && id < 65536 && counts[id] >= min_pixels);
    if (visible && frame.T_world_camera_gt) {
      object_camera_[id] +=
          tumPoseLine(t_depth, T_world_object.inverse() * *frame.T_world_camera_gt);
    } else if (!object_camera_.count(id)) {
      object_camera_[id] = "";
    }
  }

  if (frame.detections) {
    std::vector<const core::Detection*> order;
    for (const auto& d : *frame.detections) {
      if (d.mask.size() != frame.depth.size() || d.mask.type() != CV_32F) {
        throw IoError("TUM writer for " + dir_ + ": " + name + " detection " +
                      std::to_string(d.id) + " mask is not a CV_32F image of the depth size");
      }
      if (d.id < 1 || d.id > 65535) {
        throw IoError("TUM writer for " + dir_ + ": " + name + " detection id " +
                      std::to_string(d.id) + " is outside 1..65535");
      }
      order.push_back(&d);
    }
    // Where masks overlap the higher score wins: paint in ascending score.
    std::stable_sort(
        order.begin(), order.end(),
        [](const core::Detection* a, const core::Detection* b) { return a->score < b->score; });
    cv::Mat ids = cv::Mat::zeros(frame.depth.size(), CV_16U);
    for (const core::Detection* d : order) ids.setTo(cv::Scalar(d->id), d->mask >= 0.5f);
    // A detection hidden entirely under higher-scoring ones has no pixel left in the id image;
    // listing it would make the folder inconsistent (readers reject ids without pixels).
    std::vector<bool> present(65536, false);
    for (int y = 0; y < ids.rows; ++y) {
      const uint16_t* row = ids.ptr<uint16_t>(y);
      for (int x = 0; x < ids.cols; ++x) present[row[x]] = true;
    }
    std::string lines;
    for (const auto& d : *frame.detections) {
      if (!present[d.id]) continue;
      char line[512];
      std::snprintf(line, sizeof(line), "%d %s %.6f\n", d.id, maskClassToken(d.class_name).c_str(),
                    static_cast<double>(d.score));
      lines += line;
    }
    writeImageAtomically((fs::path(dir_) / "masks" / (t_depth + ".png")).string(), ids, png);
    writeFileAtomically((fs::path(dir_) / "masks" / (t_depth + ".txt")).string(), lines);
  }
  ++frames_;
}

void TumWriter::finish() {
  if (finished_) return;
  finished_ = true;
  const fs::path d(dir_);
  writeFileAtomically((d / "rgb.txt").string(), rgb_list_);
  writeFileAtomically((d / "depth.txt").string(), depth_list_);
  writeFileAtomically((d / "associations.txt").string(), associations_);
  writeFileAtomically((d / "groundtruth.txt").string(), groundtruth_);
  char calib[256];
  std::snprintf(calib, sizeof(calib), "%.6f %.6f %.6f %.6f %d %d\n", intrinsics_.fx, intrinsics_.fy,
                intrinsics_.cx, intrinsics_.cy, intrinsics_.width, intrinsics_.height);
  writeFileAtomically((d / "calibration.txt").string(), calib);
  for (const auto& [id, lines] : object_world_) {
    const std::string header =
        "# object " + std::to_string(id) + ": T_world_object\n# timestamp tx ty tz qx qy qz qw\n";
    writeFileAtomically(
        (d / "objects" / ("gt-object-" + std::to_string(id) + "-world.txt")).string(),
        header + lines);
  }
  for (const auto& [id, lines] : object_camera_) {
    const std::string header = "# object " + std::to_string(id) +
                               ": T_object_camera (camera pose in the object's frame), frames "
                               "where the object is visible\n# timestamp tx ty tz qx qy qz qw\n";
    writeFileAtomically(
        (d / "objects" / ("gt-object-" + std::to_string(id) + "-camera.txt")).string(),
        header + lines);
  }
  if (unrepresentable_depth_ > 0) {
    logWarning("TUM writer for ", dir_, ": ", unrepresentable_depth_,
               " depth pixels beyond 65535 / depth_scale m were written as 0 (invalid)");
  }
  char scale[64], visible_percent[64];
  std::snprintf(scale, sizeof(scale), "%g", options_.depth_scale);
  std::snprintf(visible_percent, sizeof(visible_percent), "%g",
                options_.min_visible_fraction * 100.0);
  std::string readme = "# RGB-D sequence (TUM RGB-D folder layout)\n\n";
  if (!options_.readme_about.empty()) readme += options_.readme_about + "\n\n";
  readme += "Frames: " + std::to_string(frames_) + ", " + std::to_string(intrinsics_.width) + "x" +
            std::to_string(intrinsics_.height) + ".\n\n";
  readme +=
      "## Files\n\n"
      "- `rgb/<t>.png`: colour, 8-bit 3-channel PNG.\n"
      "- `depth/<t>.png`: depth, 16-bit PNG, " +
      std::string(scale) + " units per metre (value / " + scale +
      " = metres along the optical axis), 0 = no measurement.\n"
      "- `rgb.txt`, `depth.txt`: `timestamp filename` per frame (3 comment lines first).\n"
      "- `associations.txt`: `t_rgb rgb/<t>.png t_depth depth/<t>.png` per frame.\n"
      "- `groundtruth.txt`: camera pose T_world_camera per frame, `t tx ty tz qx qy qz qw` "
      "(translation in metres, unit quaternion, camera frame x right, y down, z forward).\n"
      "- `calibration.txt`: `fx fy cx cy width height` (pixels) of the depth camera; colour is "
      "registered to depth.\n"
      "- `objects/gt-object-<k>-world.txt`: object k's pose T_world_object per frame.\n"
      "- `objects/gt-object-<k>-camera.txt`: the camera pose in object k's frame, "
      "T_object_camera, only for frames where the object is visible (at least " +
      std::string(visible_percent) +
      " % of the image). Evaluate object trajectories against this file: ATE with Horn "
      "alignment is then independent of where the object's origin lies.\n"
      "- `masks/<t>.png` and `masks/<t>.txt`: detections on the frames where the detector ran. "
      "The PNG is 16-bit, of the depth image's size, pixel = detection id 1..n (0 = none; "
      "where masks overlap the higher score wins). The text file has one line per detection, "
      "`det_id class_name score` (spaces in class names written as `_`, score in [0, 1]). "
      "Detection ids are per frame and are not object ids. `<t>` is the depth timestamp "
      "exactly as in depth.txt.\n\n"
      "Timestamps are seconds, written with 6 decimals; file names use the same text.\n";
  writeFileAtomically((d / "README.md").string(), readme);
}

}  // namespace emf::io
