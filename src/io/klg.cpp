#include "io/klg.h"

#include <zlib.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "common/error.h"
#include "common/log.h"
#include "io/depth_image.h"
#include "io/tum_source.h"

#if !defined(__BYTE_ORDER__) || __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "the KLG reader/writer assumes a little-endian host (the format is little-endian)"
#endif

namespace emf::io {
namespace {

std::string sizeText(cv::Size s) {
  return std::to_string(s.width) + "x" + std::to_string(s.height);
}

}  // namespace

// ---- reader ---------------------------------------------------------------------------------

KlgSource::KlgSource(const std::string& path, const core::SourceOptions& options, cv::Size size,
                     double depth_scale)
    : path_(path), size_(size), depth_scale_(depth_scale) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw IoError("KLG file '" + path + "' does not exist or is not a file");
  }
  file_size_ = std::filesystem::file_size(path, ec);
  in_.open(path, std::ios::binary);
  if (!in_ || ec) throw IoError("cannot open KLG file '" + path + "'");
  if (size.width <= 0 || size.height <= 0) {
    throw IoError("KLG file '" + path + "': image size " + sizeText(size) + " is not valid");
  }
  readExact(&frame_count_, sizeof(frame_count_), -1, "frame count");
  if (frame_count_ < 0) {
    throw IoError("KLG file '" + path + "': frame count " + std::to_string(frame_count_) +
                  " is negative; not a KLG file?");
  }
  // A recorder that did not close its file leaves the count it wrote first (0; KlgWriter too),
  // or a stale one: the frames after it would be ignored without a word.
  const int64_t complete = countCompleteFrames();
  if (complete > frame_count_) {
    logWarning("KLG file '", path, "': the header announces ", frame_count_,
               " frames but the file holds ", complete,
               " complete frames (a recording that was not closed?); reading all ", complete);
    frame_count_ = static_cast<int32_t>(complete);
  }
  frames_to_read_ = frame_count_;
  if (options.max_frames > 0 && frames_to_read_ > options.max_frames) {
    frames_to_read_ = options.max_frames;
  }
  intrinsics_ = resolveIntrinsics(options, "", size, "KLG file '" + path + "' (stores none)");
}

int64_t KlgSource::countCompleteFrames() {
  int64_t n = 0;
  uint64_t at = sizeof(int32_t);
  constexpr uint64_t kHeader = sizeof(int64_t) + 2 * sizeof(int32_t);
  while (at + kHeader <= file_size_ && n < std::numeric_limits<int32_t>::max()) {
    struct {
      int64_t timestamp_us;
      int32_t depth_size, image_size;
    } h;
    in_.seekg(static_cast<std::streamoff>(at));
    if (!in_.read(reinterpret_cast<char*>(&h.timestamp_us), 8) ||
        !in_.read(reinterpret_cast<char*>(&h.depth_size), 4) ||
        !in_.read(reinterpret_cast<char*>(&h.image_size), 4) || h.depth_size <= 0 ||
        h.image_size < 0 ||
        at + kHeader + static_cast<uint64_t>(h.depth_size) + static_cast<uint64_t>(h.image_size) >
            file_size_) {
      break;
    }
    at += kHeader + static_cast<uint64_t>(h.depth_size) + static_cast<uint64_t>(h.image_size);
    ++n;
  }
  in_.clear();
  in_.seekg(static_cast<std::streamoff>(offset_));
  return n;
}

void KlgSource::readExact(void* dst, size_t bytes, int64_t frame, const char* what) {
  if (offset_ + bytes > file_size_ ||
      !in_.read(static_cast<char*>(dst), static_cast<std::streamsize>(bytes))) {
    throw IoError("KLG file '" + path_ + "'" +
                  (frame >= 0 ? ", frame " + std::to_string(frame) : std::string()) +
                  ": file ends at byte " + std::to_string(file_size_) + " while reading the " +
                  what + " (" + std::to_string(bytes) + " bytes at byte " +
                  std::to_string(offset_) + ")" +
                  (frame >= 0 ? "; the header announces " + std::to_string(frame_count_) +
                                    " frames: truncated recording?"
                              : std::string(": not a KLG file (empty or truncated)")));
  }
  offset_ += bytes;
}

bool KlgSource::next(core::Frame& frame) {
  if (cursor_ >= frames_to_read_) return false;
  const int64_t i = cursor_;
  const uint64_t frame_offset = offset_;
  int64_t timestamp_us = 0;
  int32_t depth_size = 0, image_size = 0;
  readExact(&timestamp_us, sizeof(timestamp_us), i, "timestamp");
  readExact(&depth_size, sizeof(depth_size), i, "depth size");
  readExact(&image_size, sizeof(image_size), i, "image size");
  const std::string where = "KLG file '" + path_ + "', frame " + std::to_string(i) + " (at byte " +
                            std::to_string(frame_offset) + ")";
  if (depth_size <= 0 || image_size < 0) {
    throw IoError(where + ": depth size " + std::to_string(depth_size) + " / image size " +
                  std::to_string(image_size) + " are not valid; corrupt file");
  }
  // Check the sizes against the rest of the file before allocating (a corrupt size must not
  // become a multi-gigabyte allocation).
  const uint64_t remaining = file_size_ - offset_;
  if (static_cast<uint64_t>(depth_size) + static_cast<uint64_t>(image_size) > remaining) {
    throw IoError(where + ": depth size " + std::to_string(depth_size) + " + image size " +
                  std::to_string(image_size) + " bytes exceed the " + std::to_string(remaining) +
                  " bytes left in the file (of " + std::to_string(file_size_) +
                  "); the header announces " + std::to_string(frame_count_) +
                  " frames: truncated recording or corrupt file");
  }
  if (i > 0 && timestamp_us <= last_timestamp_us_) {
    throw IoError(where + ": timestamp " + std::to_string(timestamp_us) +
                  " us is not after the previous frame's (" + std::to_string(last_timestamp_us_) +
                  " us); timestamps must increase");
  }
  last_timestamp_us_ = timestamp_us;

  const size_t pixels = static_cast<size_t>(size_.area());
  std::vector<unsigned char> depth_bytes(static_cast<size_t>(depth_size));
  readExact(depth_bytes.data(), depth_bytes.size(), i, "depth image");
  cv::Mat units(size_, CV_16UC1);
  if (depth_bytes.size() == pixels * 2) {
    std::memcpy(units.data, depth_bytes.data(), pixels * 2);
  } else {
    uLongf out_len = static_cast<uLongf>(pixels * 2);
    const int rc = uncompress(units.data, &out_len, depth_bytes.data(),
                              static_cast<uLong>(depth_bytes.size()));
    if (rc != Z_OK || out_len != pixels * 2) {
      throw IoError(where + ": depth (" + std::to_string(depth_size) +
                    " bytes) does not decompress to " + sizeText(size_) + " uint16 pixels (zlib: " +
                    (rc == Z_OK ? "size " + std::to_string(out_len) : std::string(zError(rc))) +
                    "); pass the right ?width=&height= or check the file");
    }
  }
  core::Frame f;
  f.index = i;
  f.timestamp = f.rgb_timestamp = static_cast<double>(timestamp_us) * 1e-6;
  char text[64];
  std::snprintf(text, sizeof(text), "%.6f", f.timestamp);
  f.timestamp_text = text;
  f.depth = depthFromUnits(units, depth_scale_);
  if (i == 0) {
    const std::string scale_warning = depthScaleWarning(units, depth_scale_);
    if (!scale_warning.empty()) logWarning("KLG file '", path_, "', frame 0: ", scale_warning);
  }
  if (image_size > 0) {
    std::vector<unsigned char> image_bytes(static_cast<size_t>(image_size));
    readExact(image_bytes.data(), image_bytes.size(), i, "colour image");
    if (image_bytes.size() == pixels * 3) {
      cv::Mat rgb(size_, CV_8UC3, image_bytes.data());
      cv::cvtColor(rgb, f.color, cv::COLOR_RGB2BGR);
    } else {
      f.color = cv::imdecode(image_bytes, cv::IMREAD_COLOR);
      if (f.color.empty()) {
        throw IoError(where + ": colour image (" + std::to_string(image_size) +
                      " bytes) is not a decodable JPEG; corrupt file");
      }
    }
  }
  frame = std::move(f);
  ++cursor_;
  return true;
}

std::string KlgSource::describe() const {
  return "KLG file " + path_ + ", " + std::to_string(frames_to_read_) + " frames " +
         sizeText(size_);
}

// ---- writer ---------------------------------------------------------------------------------

KlgWriter::KlgWriter(const std::string& path, double depth_scale, int jpeg_quality)
    : out_(std::make_unique<AtomicOutputFile>(path)),
      depth_scale_(depth_scale),
      jpeg_quality_(jpeg_quality) {
  if (!(depth_scale > 0) || jpeg_quality < 0 || jpeg_quality > 100) {
    throw InvalidArgument("KlgWriter: depth_scale must be > 0 and jpeg_quality in 0..100");
  }
  const int32_t placeholder = 0;
  out_->write(&placeholder, sizeof(placeholder));
}

void KlgWriter::write(const core::Frame& frame) {
  if (!out_) throw InvalidArgument("KlgWriter: write() after close()");
  const std::string which = "KlgWriter '" + out_->path() + "', frame " + std::to_string(frames_);
  if (frame.depth.empty() || frame.depth.type() != CV_32FC1) {
    throw InvalidArgument(which + ": depth must be a non-empty CV_32F image in metres");
  }
  if (frames_ == 0) {
    size_ = frame.depth.size();
  } else if (frame.depth.size() != size_) {
    throw InvalidArgument(which + ": depth is " + sizeText(frame.depth.size()) +
                          " but the first frame's is " + sizeText(size_));
  }
  if (!frame.color.empty() && frame.color.type() != CV_8UC3) {
    throw InvalidArgument(which + ": colour must be CV_8UC3 BGR or empty");
  }
  const double us = std::round(frame.timestamp * 1e6);
  if (!(std::abs(us) < 9e18)) throw InvalidArgument(which + ": timestamp is not finite");
  const int64_t timestamp_us = static_cast<int64_t>(us);
  if (frames_ > 0 && timestamp_us <= last_timestamp_us_) {
    throw InvalidArgument(which + ": timestamp " + std::to_string(frame.timestamp) +
                          " s is not after the previous frame's");
  }

  const cv::Mat units = depthToUnits(frame.depth, depth_scale_);
  const uLong raw_bytes = static_cast<uLong>(units.total() * units.elemSize());
  std::vector<unsigned char> depth_z(compressBound(raw_bytes));
  uLongf depth_len = static_cast<uLongf>(depth_z.size());
  const cv::Mat cont = units.isContinuous() ? units : units.clone();
  if (compress2(depth_z.data(), &depth_len, cont.data, raw_bytes, Z_BEST_SPEED) != Z_OK) {
    throw IoError(which + ": zlib compression failed");
  }
  // A compressed block of exactly width*height*2 bytes would be read back as raw depth; store
  // the raw block instead (readers treat that size as uncompressed).
  const unsigned char* depth_data = depth_z.data();
  if (depth_len == raw_bytes) depth_data = cont.data;

  std::vector<unsigned char> jpeg;
  if (!frame.color.empty()) {
    if (!cv::imencode(".jpg", frame.color, jpeg, {cv::IMWRITE_JPEG_QUALITY, jpeg_quality_})) {
      throw IoError(which + ": JPEG encoding failed");
    }
    // A JPEG of exactly width*height*3 bytes would be taken for raw RGB: pad it (decoders
    // ignore bytes after the end-of-image marker).
    if (jpeg.size() == static_cast<size_t>(size_.area()) * 3) jpeg.push_back(0);
  }
  const int32_t depth_size = static_cast<int32_t>(depth_len);
  const int32_t image_size = static_cast<int32_t>(jpeg.size());
  out_->write(&timestamp_us, sizeof(timestamp_us));
  out_->write(&depth_size, sizeof(depth_size));
  out_->write(&image_size, sizeof(image_size));
  out_->write(depth_data, depth_len);
  out_->write(jpeg.data(), jpeg.size());
  last_timestamp_us_ = timestamp_us;
  ++frames_;
}

void KlgWriter::close() {
  if (!out_) return;
  if (frames_ > std::numeric_limits<int32_t>::max()) {
    throw IoError("KlgWriter '" + out_->path() + "': too many frames for the int32 count");
  }
  const int32_t count = static_cast<int32_t>(frames_);
  out_->writeAt(0, &count, sizeof(count));
  out_->commit();
  out_.reset();
}

}  // namespace emf::io
