#include "io/tum_source.h"

#include <filesystem>
#include <map>
#include <set>

#include "common/error.h"
#include "common/log.h"
#include "io/depth_image.h"
#include "io/detections_io.h"
#include "io/text_table.h"

namespace emf::io {
namespace fs = std::filesystem;
namespace {

// Maximum time between a depth frame and the ground-truth poses used for it.
constexpr double kGroundTruthMaxDiffS = 0.02;

struct ListEntry {
  double stamp;
  std::string stamp_text, file;
  int line;
};

// Reads a `timestamp file` list, requiring strictly increasing timestamps.
std::vector<ListEntry> readStampList(const std::string& path) {
  std::vector<ListEntry> out;
  for (const TableRow& row : readTable(path)) {
    expectFields(row, 2, path, "timestamp filename");
    const double t = parseFinite(row.fields[0], path, row.line, "timestamp");
    if (!out.empty() && !(t > out.back().stamp)) {
      throw IoError(fileLine(path, row.line) + ": timestamp " + row.fields[0] +
                    " is not after the previous one (" + out.back().stamp_text + " on line " +
                    std::to_string(out.back().line) + "); timestamps must increase");
    }
    out.push_back({t, row.fields[0], row.fields[1], row.line});
  }
  return out;
}

std::string sizeText(cv::Size s) {
  return std::to_string(s.width) + "x" + std::to_string(s.height);
}

}  // namespace

core::Intrinsics readCalibrationFile(const std::string& path) {
  const auto rows = readTable(path);
  if (rows.empty()) throw IoError("'" + path + "' is empty; expected `fx fy cx cy [width height]`");
  const TableRow& row = rows.front();
  if (rows.size() > 1) {
    throw IoError(fileLine(path, rows[1].line) +
                  ": expected one line `fx fy cx cy [width height]`, found more");
  }
  if (row.fields.size() != 4 && row.fields.size() != 6) {
    throw IoError(fileLine(path, row.line) + ": expected 4 or 6 fields (fx fy cx cy [width " +
                  "height]), got " + std::to_string(row.fields.size()));
  }
  core::Intrinsics k;
  k.fx = parseFinite(row.fields[0], path, row.line, "fx");
  k.fy = parseFinite(row.fields[1], path, row.line, "fy");
  k.cx = parseFinite(row.fields[2], path, row.line, "cx");
  k.cy = parseFinite(row.fields[3], path, row.line, "cy");
  if (k.fx <= 0 || k.fy <= 0) {
    throw IoError(fileLine(path, row.line) + ": focal lengths must be positive");
  }
  if (row.fields.size() == 6) {
    const long long w = parseInteger(row.fields[4], path, row.line, "width");
    const long long h = parseInteger(row.fields[5], path, row.line, "height");
    if (w <= 0 || h <= 0 || w > 100000 || h > 100000) {
      throw IoError(fileLine(path, row.line) + ": image size " + row.fields[4] + "x" +
                    row.fields[5] + " is not plausible");
    }
    k.width = static_cast<int>(w);
    k.height = static_cast<int>(h);
  }
  return k;
}

core::Intrinsics resolveIntrinsics(const core::SourceOptions& options,
                                   const std::string& calibration_path, cv::Size size,
                                   const std::string& what) {
  core::Intrinsics k;
  const int given = (options.fx > 0) + (options.fy > 0) + (options.cx > 0) + (options.cy > 0);
  if (given == 4) {
    k.fx = options.fx;
    k.fy = options.fy;
    k.cx = options.cx;
    k.cy = options.cy;
  } else if (given > 0) {
    std::string missing;
    if (options.fx <= 0) missing += " fx";
    if (options.fy <= 0) missing += " fy";
    if (options.cx <= 0) missing += " cx";
    if (options.cy <= 0) missing += " cy";
    throw IoError(what + ": intrinsics only partly given (missing:" + missing +
                  "); pass all of fx, fy, cx, cy (URI query or config section source)");
  } else if (!calibration_path.empty() && fs::exists(calibration_path)) {
    k = readCalibrationFile(calibration_path);
    if (k.width != 0 && (k.width != size.width || k.height != size.height)) {
      throw IoError(calibration_path + ": calibration is for " + std::to_string(k.width) + "x" +
                    std::to_string(k.height) + " images but the depth images are " +
                    sizeText(size));
    }
  } else {
    throw IoError(what + ": no intrinsics: " +
                  (calibration_path.empty()
                       ? std::string()
                       : "add " + calibration_path + " (`fx fy cx cy width height`) or ") +
                  "pass them as ?fx=..&fy=..&cx=..&cy=.. (or source.fx/fy/cx/cy in the config). "
                  "They are not guessed; e.g. TUM fr1 517.3 516.5 318.6 255.3, fr2 520.9 521.0 "
                  "325.1 249.7, fr3 535.4 539.2 320.1 247.6, 7-Scenes 585 585 320 240");
  }
  k.width = size.width;
  k.height = size.height;
  // A calibration file's values are checked here, so the error names the file; values from the
  // URI or the configuration are checked (and named) when the SLAM starts.
  if (given == 0) {
    try {
      core::checkedIntrinsics(k);
    } catch (const InvalidArgument& e) {
      throw IoError(calibration_path + ": " + e.what());
    }
  }
  return k;
}

TumSource::TumSource(const std::string& dir, const core::SourceOptions& options)
    : dir_(dir), options_(options) {
  if (!fs::is_directory(dir)) {
    throw IoError("TUM folder '" + dir + "' does not exist or is not a folder");
  }
  const fs::path root(dir);
  const std::string assoc_path = (root / "associations.txt").string();
  const std::string depth_path = (root / "depth.txt").string();
  const std::string rgb_path = (root / "rgb.txt").string();

  // depth.txt gives the canonical timestamp text of each depth file (detections key on it).
  std::map<std::string, std::string> depth_text_by_file;
  std::vector<ListEntry> depth_list;
  if (fs::exists(depth_path)) {
    depth_list = readStampList(depth_path);
    for (const auto& e : depth_list) depth_text_by_file[e.file] = e.stamp_text;
  }

  if (fs::exists(assoc_path)) {
    const auto rows = readTable(assoc_path);
    // Recognise the depth-first order some tools write.
    bool depth_first = false;
    if (!rows.empty() && rows[0].fields.size() == 4) {
      depth_first =
          rows[0].fields[1].rfind("depth", 0) == 0 && rows[0].fields[3].rfind("rgb", 0) == 0;
    }
    for (const TableRow& row : rows) {
      expectFields(row, 4, assoc_path, "t_rgb rgb_file t_depth depth_file");
      const int di = depth_first ? 0 : 2, ri = depth_first ? 2 : 0;
      TumEntry e;
      e.rgb_stamp = parseFinite(row.fields[ri], assoc_path, row.line, "rgb timestamp");
      e.rgb_file = row.fields[ri + 1];
      e.depth_stamp = parseFinite(row.fields[di], assoc_path, row.line, "depth timestamp");
      e.depth_file = row.fields[di + 1];
      auto it = depth_text_by_file.find(e.depth_file);
      e.depth_stamp_text = it != depth_text_by_file.end() ? it->second : row.fields[di];
      e.origin = fileLine(assoc_path, row.line);
      if (!entries_.empty() && !(e.depth_stamp > entries_.back().depth_stamp)) {
        throw IoError(e.origin + ": depth timestamp " + row.fields[di] +
                      " is not after the previous line's (" + entries_.back().origin +
                      "); timestamps must increase");
      }
      entries_.push_back(std::move(e));
    }
  } else if (!depth_list.empty() || fs::exists(depth_path)) {
    std::vector<ListEntry> rgb_list;
    if (fs::exists(rgb_path)) rgb_list = readStampList(rgb_path);
    if (rgb_list.empty()) {
      logWarning("TUM folder '", dir, "': no rgb.txt entries, frames have depth only");
      for (const auto& d : depth_list) {
        entries_.push_back(
            {d.stamp, d.stamp_text, d.file, 0, "", fileLine(depth_path, d.line), ""});
      }
    } else {
      std::vector<double> ts_depth, ts_rgb;
      for (const auto& d : depth_list) ts_depth.push_back(d.stamp);
      for (const auto& r : rgb_list) ts_rgb.push_back(r.stamp);
      const auto matches = associateStamps(ts_depth, ts_rgb, options.max_time_diff_s);
      for (const auto& m : matches) {
        const ListEntry& d = depth_list[m.first];
        const ListEntry& r = rgb_list[m.second];
        entries_.push_back({d.stamp, d.stamp_text, d.file, r.stamp, r.file,
                            fileLine(depth_path, d.line), fileLine(rgb_path, r.line)});
      }
      if (matches.size() < depth_list.size()) {
        logWarning("TUM folder '", dir, "': ", depth_list.size() - matches.size(), " of ",
                   depth_list.size(), " depth frames have no rgb frame within ",
                   options.max_time_diff_s, " s and are skipped");
      }
    }
  } else {
    throw IoError("'" + dir +
                  "' is not a TUM RGB-D folder: it has neither associations.txt nor depth.txt");
  }
  if (entries_.empty() && !fs::exists(assoc_path) && !depth_list.empty()) {
    throw IoError("TUM folder '" + dir + "': none of the " + std::to_string(depth_list.size()) +
                  " depth frames of " + depth_path + " has an rgb frame within " +
                  std::to_string(options.max_time_diff_s) + " s in " + rgb_path +
                  "; check that both lists use the same clock, or raise ?max_time_diff_s=");
  }
  if (entries_.empty()) {
    throw IoError("TUM folder '" + dir + "' lists no frames (" +
                  (fs::exists(assoc_path) ? assoc_path : depth_path) + " is empty)");
  }
  if (options.max_frames > 0 && entries_.size() > static_cast<size_t>(options.max_frames)) {
    entries_.resize(static_cast<size_t>(options.max_frames));
  }

  const std::string gt_path = (root / "groundtruth.txt").string();
  if (fs::exists(gt_path)) ground_truth_ = readTrajectory(gt_path);

  first_depth_file_ = (root / entries_[0].depth_file).string();
  const cv::Mat first_units = readDepthUnits(first_depth_file_, entries_[0].origin);
  depth_size_ = first_units.size();
  const std::string scale_warning = depthScaleWarning(first_units, options.depth_scale);
  if (!scale_warning.empty()) {
    warn("TUM folder '" + dir + "', first depth image '" + first_depth_file_ +
         "': " + scale_warning);
  }
  intrinsics_ = resolveIntrinsics(options, (root / "calibration.txt").string(), depth_size_,
                                  "TUM folder '" + dir + "'");
  if (fs::is_directory(root / "masks")) {
    masks_dir_ = (root / "masks").string();
    checkMasksMatchFrames();
  }
}

void TumSource::warn(const std::string& text) {
  logWarning(text);
  open_warnings_.push_back(text);
}

void TumSource::checkMasksMatchFrames() {
  // Detections are looked up by the frame's depth timestamp text: a folder written with other
  // digits (7 decimals instead of 6) would give no detections at all without a word.
  std::set<std::string> lists;
  std::string example;
  for (const auto& e : fs::directory_iterator(masks_dir_)) {
    if (e.path().extension() != ".txt") continue;
    lists.insert(e.path().stem().string());
    if (example.empty() || e.path().stem().string() < example) example = e.path().stem().string();
  }
  if (lists.empty()) return;
  for (const TumEntry& e : entries_) {
    if (lists.count(e.depth_stamp_text)) return;
  }
  warn("TUM folder '" + dir_ + "': masks/ has " + std::to_string(lists.size()) +
       " detection list(s) but none is named after a frame's depth timestamp (first frame: '" +
       entries_[0].depth_stamp_text + ".txt', masks/ has e.g. '" + example +
       ".txt'): they are matched by the timestamp text exactly, so no frame gets detections; "
       "rename them after depth.txt's timestamps");
}

core::Frame TumSource::readFrame(size_t index) const {
  const TumEntry& e = entries_.at(index);
  const fs::path root(dir_);
  core::Frame f;
  f.index = static_cast<int64_t>(index);
  f.timestamp = e.depth_stamp;
  f.timestamp_text = e.depth_stamp_text;
  f.rgb_timestamp = e.rgb_stamp;
  const std::string depth_file = (root / e.depth_file).string();
  const cv::Mat units = readDepthUnits(depth_file, e.origin);
  if (units.size() != depth_size_) {
    throw IoError(e.origin + ": depth image '" + depth_file + "' is " + sizeText(units.size()) +
                  " but the first frame's ('" + first_depth_file_ + "') is " +
                  sizeText(depth_size_) + "; all frames must have the same size");
  }
  f.depth = depthFromUnits(units, options_.depth_scale);
  if (!e.rgb_file.empty()) {
    const std::string color_file = (root / e.rgb_file).string();
    const std::string& color_origin = e.color_origin.empty() ? e.origin : e.color_origin;
    f.color = readColor(color_file, color_origin);
    if (color_size_.area() == 0) {
      color_size_ = f.color.size();
      first_color_file_ = color_file;
    } else if (f.color.size() != color_size_) {
      throw IoError(color_origin + ": colour image '" + color_file + "' is " +
                    sizeText(f.color.size()) + " but '" + first_color_file_ + "' is " +
                    sizeText(color_size_) + "; all frames must have the same size");
    }
  }
  if (!ground_truth_.empty()) {
    if (auto T = poseAt(ground_truth_, e.depth_stamp, kGroundTruthMaxDiffS)) {
      f.T_world_camera_gt = *T;
    }
  }
  if (!masks_dir_.empty()) {
    // The source's copy is only informative (the maskfile plugin reads masks/ itself and
    // reports its own failures): a broken mask must not stop a run that uses no detector.
    try {
      f.detections = readFrameDetections(masks_dir_, e.depth_stamp_text, depth_size_);
    } catch (const IoError& err) {
      if (bad_masks_++ == 0) {
        logWarning(err.what(), "; frame ", index,
                   " is read without its detections (a run with --detector maskfile reports "
                   "the same file as a detector failure)");
      }
    }
  }
  return f;
}

bool TumSource::next(core::Frame& frame) {
  if (cursor_ >= entries_.size()) return false;
  frame = readFrame(cursor_);
  ++cursor_;
  return true;
}

std::string TumSource::describe() const {
  return "TUM folder " + dir_ + ", " + std::to_string(entries_.size()) + " frames " +
         sizeText(depth_size_) + (ground_truth_.empty() ? "" : ", ground truth") +
         (masks_dir_.empty() ? "" : ", detections");
}

// ---- tum-fr1-xyz-pairs ------------------------------------------------------------------------

core::Intrinsics readIntrinsicMatrix(const std::string& path) {
  const auto rows = readTable(path);
  if (rows.size() != 3) {
    throw IoError("'" + path + "': expected a 3x3 intrinsic matrix on 3 lines, found " +
                  std::to_string(rows.size()) + " lines");
  }
  double m[3][3];
  for (int r = 0; r < 3; ++r) {
    expectFields(rows[r], 3, path, "one row of the 3x3 matrix");
    for (int c = 0; c < 3; ++c) {
      m[r][c] = parseFinite(rows[r].fields[c], path, rows[r].line, "matrix entry");
    }
  }
  if (m[0][0] <= 0 || m[1][1] <= 0 || m[2][2] != 1.0 || m[1][0] != 0 || m[2][0] != 0 ||
      m[2][1] != 0) {
    throw IoError("'" + path + "': not an intrinsic matrix (expected fx 0 cx / 0 fy cy / 0 0 1)");
  }
  core::Intrinsics k;
  k.fx = m[0][0];
  k.fy = m[1][1];
  k.cx = m[0][2];
  k.cy = m[1][2];
  return k;
}

namespace {

Eigen::Isometry3d readPoseFile(const std::string& path) {
  const auto rows = readTable(path);
  if (rows.size() != 1) {
    throw IoError("'" + path + "': expected one line `tx ty tz qx qy qz qw`, found " +
                  std::to_string(rows.size()));
  }
  expectFields(rows[0], 7, path, "tx ty tz qx qy qz qw");
  double v[7];
  for (int i = 0; i < 7; ++i) v[i] = parseFinite(rows[0].fields[i], path, rows[0].line, "value");
  const auto T = poseFromTum(v[0], v[1], v[2], v[3], v[4], v[5], v[6]);
  if (!T) throw IoError(fileLine(path, rows[0].line) + ": quaternion is not of unit norm");
  return *T;
}

core::Frame readPairFrame(const fs::path& dir, const std::string& tag, double depth_scale,
                          int64_t index) {
  core::Frame f;
  f.index = index;
  f.timestamp = f.rgb_timestamp = static_cast<double>(index);
  f.timestamp_text = std::to_string(index);
  const std::string depth_file = (dir / ("dep_" + tag + ".png")).string();
  f.depth = depthFromUnits(readDepthUnits(depth_file, dir.string()), depth_scale);
  f.color = readColor((dir / ("img_" + tag + ".png")).string(), dir.string());
  f.T_world_camera_gt = readPoseFile((dir / ("pose_" + tag + ".txt")).string());
  return f;
}

}  // namespace

Eigen::Isometry3d TumPairCase::T_prev_curr() const {
  return prev.T_world_camera_gt->inverse() * *curr.T_world_camera_gt;
}

TumPairCase loadTumPairCase(const std::string& case_dir, const std::string& intrinsics_path,
                            double depth_scale) {
  if (!fs::is_directory(case_dir)) throw IoError("pair case '" + case_dir + "' is not a folder");
  TumPairCase c;
  c.prev = readPairFrame(case_dir, "prev", depth_scale, 0);
  c.curr = readPairFrame(case_dir, "curr", depth_scale, 1);
  if (c.prev.depth.size() != c.curr.depth.size()) {
    throw IoError("pair case '" + case_dir + "': dep_prev.png and dep_curr.png differ in size");
  }
  c.intrinsics = readIntrinsicMatrix(intrinsics_path);
  c.intrinsics.width = c.prev.depth.cols;
  c.intrinsics.height = c.prev.depth.rows;
  return c;
}

}  // namespace emf::io
