#include "io/detections_io.h"

#include <algorithm>
#include <filesystem>
#include <map>
#include <opencv2/imgcodecs.hpp>

#include "common/error.h"
#include "io/depth_image.h"
#include "io/text_table.h"

namespace emf::io {
namespace fs = std::filesystem;

std::vector<core::Detection> readDetectionFiles(const std::string& png_path,
                                                const std::string& txt_path, cv::Size image_size) {
  // The list first: ids, classes, scores.
  struct Label {
    std::string class_name;
    float score;
    int line;
  };
  std::map<int, Label> labels;
  for (const TableRow& row : readTable(txt_path)) {
    expectFields(row, 3, txt_path, "det_id class_name score, '_' for spaces in class names");
    const long long id = parseInteger(row.fields[0], txt_path, row.line, "detection id");
    if (id < 1 || id > 65535) {
      throw IoError(fileLine(txt_path, row.line) + ": detection id " + row.fields[0] +
                    " is outside 1..65535");
    }
    if (labels.count(static_cast<int>(id))) {
      throw IoError(fileLine(txt_path, row.line) + ": detection id " + row.fields[0] +
                    " is listed twice (also on line " +
                    std::to_string(labels[static_cast<int>(id)].line) + ")");
    }
    const double score = parseFinite(row.fields[2], txt_path, row.line, "score");
    if (score < 0.0 || score > 1.0) {
      throw IoError(fileLine(txt_path, row.line) + ": score " + row.fields[2] +
                    " is outside [0, 1]");
    }
    std::string name = row.fields[1];
    std::replace(name.begin(), name.end(), '_', ' ');
    labels[static_cast<int>(id)] = {name, static_cast<float>(score), row.line};
  }

  // Then the id image.
  if (!fs::exists(png_path)) {
    throw IoError("detection mask '" + png_path + "' does not exist but '" + txt_path +
                  "' does; write both files for a labelled frame");
  }
  const cv::Mat ids = readImageFile(png_path, cv::IMREAD_UNCHANGED, "detection mask", "");
  if (ids.empty())
    throw IoError("cannot decode detection mask '" + png_path + "' (corrupt or not a PNG)");
  if (ids.type() != CV_16UC1) {
    throw IoError("detection mask '" + png_path + "' is " + describeMatType(ids.type()) +
                  "; expected a 16-bit single-channel PNG (pixel = detection id, 0 = none)");
  }
  if (ids.size() != image_size) {
    throw IoError("detection mask '" + png_path + "' is " + std::to_string(ids.cols) + "x" +
                  std::to_string(ids.rows) + " but the depth image is " +
                  std::to_string(image_size.width) + "x" + std::to_string(image_size.height));
  }

  // Bounding boxes and pixel counts per id in one pass.
  struct Extent {
    int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
    long pixels = 0;
  };
  std::map<int, Extent> extents;
  for (int y = 0; y < ids.rows; ++y) {
    const uint16_t* row = ids.ptr<uint16_t>(y);
    for (int x = 0; x < ids.cols; ++x) {
      if (row[x] == 0) continue;
      Extent& e = extents[row[x]];
      e.x0 = std::min(e.x0, x);
      e.y0 = std::min(e.y0, y);
      e.x1 = std::max(e.x1, x);
      e.y1 = std::max(e.y1, y);
      ++e.pixels;
    }
  }
  for (const auto& [id, e] : extents) {
    if (!labels.count(id)) {
      throw IoError("detection mask '" + png_path + "' has " + std::to_string(e.pixels) +
                    " pixels with id " + std::to_string(id) + " but '" + txt_path +
                    "' has no line for detection " + std::to_string(id));
    }
  }
  std::vector<core::Detection> out;
  for (const auto& [id, label] : labels) {
    auto it = extents.find(id);
    if (it == extents.end()) {
      throw IoError(fileLine(txt_path, label.line) + ": detection " + std::to_string(id) +
                    " has no pixels in '" + png_path + "'");
    }
    const Extent& e = it->second;
    core::Detection d;
    d.id = id;
    d.class_name = label.class_name;
    d.score = label.score;
    d.box = cv::Rect(e.x0, e.y0, e.x1 - e.x0 + 1, e.y1 - e.y0 + 1);
    cv::Mat mask8 = (ids == id);  // 255 where id
    mask8.convertTo(d.mask, CV_32F, 1.0 / 255.0);
    out.push_back(std::move(d));
  }
  return out;
}

std::optional<std::vector<core::Detection>> readFrameDetections(const std::string& masks_dir,
                                                                const std::string& timestamp_text,
                                                                cv::Size image_size) {
  const std::string png = (fs::path(masks_dir) / (timestamp_text + ".png")).string();
  const std::string txt = (fs::path(masks_dir) / (timestamp_text + ".txt")).string();
  const bool has_png = fs::exists(png), has_txt = fs::exists(txt);
  if (!has_png && !has_txt) return std::nullopt;
  if (!has_txt) {
    throw IoError("detection list '" + txt + "' does not exist but its mask '" + png +
                  "' does; write both files for a labelled frame");
  }
  return readDetectionFiles(png, txt, image_size);
}

}  // namespace emf::io
