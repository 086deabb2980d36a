// Reading detections stored beside a dataset (docs/inputs_outputs.md#detections-on-disk):
//   masks/<timestamp>.png  uint16 PNG of the depth image's size; pixel = detection id 1..n,
//                          0 = no detection (so masks of one frame do not overlap)
//   masks/<timestamp>.txt  one line per detection: `det_id class_name score`, spaces in class
//                          names written as '_'; score in [0, 1]; '#' comments allowed
// <timestamp> is the frame's depth timestamp exactly as written in depth.txt. A frame with
// both files and no ids is a frame the detector ran on and found nothing.
// The writer lives with the TUM folder writer (src/io/tum_writer.h).
#pragma once

#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/frame.h"

namespace emf::io {

/// Reads one frame's detections from `png_path` and `txt_path`. Detections are sorted by id;
/// each has `box` = the bounding box of its pixels and `mask` = CV_32F 0/1 of the image size;
/// class names have '_' turned back into spaces. Throws IoError naming the file (and line) when
/// a file is missing or unreadable, the PNG is not 16-bit single-channel or not `image_size`,
/// a line is malformed, an id or score is invalid or duplicated, or the ids of the PNG and the
/// text file differ.
std::vector<core::Detection> readDetectionFiles(const std::string& png_path,
                                                const std::string& txt_path, cv::Size image_size);

/// The detections of the frame with depth timestamp `timestamp_text` in `masks_dir`, or
/// nullopt when neither `<timestamp>.png` nor `<timestamp>.txt` exists there (the frame was
/// not labelled). One of the two files without the other is an error.
std::optional<std::vector<core::Detection>> readFrameDetections(const std::string& masks_dir,
                                                                const std::string& timestamp_text,
                                                                cv::Size image_size);

}  // namespace emf::io
