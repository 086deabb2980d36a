#include "firmware_host/openni2/virtual_device/tum_folder.h"

#include <jpeglib.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

namespace emf::fw::virtual_device {
namespace {

std::string joinPath(const std::string& dir, const std::string& name) {
  if (!name.empty() && name[0] == '/') return name;
  if (!dir.empty() && dir.back() == '/') return dir + name;
  return dir + "/" + name;
}

/// Reads a TUM list file (`timestamp filename` per line, '#' comments). Also picks up a
/// `depth scale N` note from the comments.
bool readList(const std::string& path, std::vector<double>* stamps, std::vector<std::string>* files,
              double* depth_scale_note, std::string* error) {
  std::ifstream in(path);
  if (!in) {
    *error = path + ": cannot open (a TUM folder needs depth.txt and rgb.txt)";
    return false;
  }
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos) continue;
    if (line[first] == '#') {
      const size_t k = line.find("depth scale");
      if (depth_scale_note && k != std::string::npos) {
        const double v = std::atof(line.c_str() + k + std::strlen("depth scale"));
        if (v > 0) *depth_scale_note = v;
      }
      continue;
    }
    std::istringstream fields(line);
    double t = 0;
    std::string name;
    if (!(fields >> t >> name) || !std::isfinite(t)) {
      *error = path + ":" + std::to_string(line_no) + ": expected `timestamp filename`, got '" +
               line + "'";
      return false;
    }
    if (t < 0) {
      *error = path + ":" + std::to_string(line_no) + ": timestamp " + std::to_string(t) +
               " is negative; a device's timestamps are unsigned microseconds (shift the list's "
               "timestamps to start at 0 or later)";
      return false;
    }
    if (!stamps->empty() && t < stamps->back()) {
      *error = path + ":" + std::to_string(line_no) + ": timestamp " + std::to_string(t) +
               " is earlier than the previous line's; list files must be in time order";
      return false;
    }
    stamps->push_back(t);
    files->push_back(name);
  }
  return true;
}

struct JpegError {
  jpeg_error_mgr mgr;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void onJpegError(j_common_ptr cinfo) {
  JpegError* e = reinterpret_cast<JpegError*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, e->message);
  std::longjmp(e->jump, 1);
}

/// libjpeg reports errors by longjmp: this function keeps only trivially destructible locals
/// between setjmp and the decoder calls; `rgb` belongs to the caller.
bool decodeJpeg(const uint8_t* data, size_t size, std::vector<uint8_t>* rgb, int* width,
                int* height, char* message) {
  jpeg_decompress_struct cinfo;
  JpegError err;
  cinfo.err = jpeg_std_error(&err.mgr);
  err.mgr.error_exit = onJpegError;
  err.message[0] = '\0';
  if (setjmp(err.jump)) {
    std::snprintf(message, JMSG_LENGTH_MAX, "%s", err.message);
    jpeg_destroy_decompress(&cinfo);
    return false;
  }
  jpeg_create_decompress(&cinfo);
  jpeg_mem_src(&cinfo, data, static_cast<unsigned long>(size));
  jpeg_read_header(&cinfo, TRUE);
  cinfo.out_color_space = JCS_RGB;
  jpeg_start_decompress(&cinfo);
  *width = static_cast<int>(cinfo.output_width);
  *height = static_cast<int>(cinfo.output_height);
  rgb->resize(static_cast<size_t>(*width) * static_cast<size_t>(*height) * 3);
  while (cinfo.output_scanline < cinfo.output_height) {
    JSAMPROW row = rgb->data() + static_cast<size_t>(cinfo.output_scanline) * (*width) * 3;
    jpeg_read_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_decompress(&cinfo);
  jpeg_destroy_decompress(&cinfo);
  return true;
}

bool readFile(const std::string& path, std::vector<uint8_t>* bytes, std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *error = path + ": cannot open";
    return false;
  }
  bytes->assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return true;
}

/// Reads a PNG with libpng's simplified API (no setjmp needed) in the given output format.
bool readPng(const std::string& path, png_uint_32 format, std::vector<uint8_t>* pixels, int* width,
             int* height, png_uint_32* file_format, std::string* error) {
  png_image image;
  std::memset(&image, 0, sizeof(image));
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&image, path.c_str())) {
    *error = path + ": not a readable PNG (" + image.message + ")";
    png_image_free(&image);
    return false;
  }
  *file_format = image.format;
  image.format = format;
  pixels->resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, pixels->data(), 0, nullptr)) {
    *error = path + ": PNG decoding failed (" + image.message + ")";
    png_image_free(&image);
    return false;
  }
  *width = static_cast<int>(image.width);
  *height = static_cast<int>(image.height);
  return true;
}

}  // namespace

bool readDepthPng(const std::string& path, std::vector<uint16_t>* pixels, int* width, int* height,
                  std::string* error) {
  std::vector<uint8_t> bytes;
  png_uint_32 file_format = 0;
  if (!readPng(path, PNG_FORMAT_LINEAR_Y, &bytes, width, height, &file_format, error)) {
    return false;
  }
  // 16-bit files without gamma information are read unchanged (linear); anything else would be
  // converted, so insist on the TUM convention.
  if ((file_format & PNG_FORMAT_FLAG_COLOR) || !(file_format & PNG_FORMAT_FLAG_LINEAR)) {
    *error = path + ": depth PNG must be 16-bit single-channel (TUM uint16 depth)";
    return false;
  }
  pixels->resize(bytes.size() / 2);
  std::memcpy(pixels->data(), bytes.data(), pixels->size() * 2);
  return true;
}

bool readColorRgb(const std::string& path, std::vector<uint8_t>* rgb, int* width, int* height,
                  std::string* error) {
  std::vector<uint8_t> bytes;
  if (!readFile(path, &bytes, error)) return false;
  if (bytes.size() >= 3 && bytes[0] == 0xff && bytes[1] == 0xd8) {
    char message[JMSG_LENGTH_MAX] = {0};
    if (!decodeJpeg(bytes.data(), bytes.size(), rgb, width, height, message)) {
      *error = path + ": JPEG decoding failed (" + message + ")";
      return false;
    }
    return true;
  }
  png_uint_32 file_format = 0;
  return readPng(path, PNG_FORMAT_RGB, rgb, width, height, &file_format, error);
}

bool TumFolder::load(const std::string& dir, double depth_scale_override, TumFolder* out,
                     std::string* error) {
  TumFolder f;
  f.dir = dir;
  double scale_note = 0;
  std::vector<std::string> names;
  if (!readList(joinPath(dir, "depth.txt"), &f.depth_timestamps_s, &names, &scale_note, error)) {
    return false;
  }
  for (const auto& n : names) f.depth_files.push_back(joinPath(dir, n));
  names.clear();
  if (!readList(joinPath(dir, "rgb.txt"), &f.rgb_timestamps_s, &names, nullptr, error)) {
    return false;
  }
  for (const auto& n : names) f.rgb_files.push_back(joinPath(dir, n));
  if (f.depth_files.empty()) {
    *error = joinPath(dir, "depth.txt") + ": no frames listed";
    return false;
  }
  f.depth_scale =
      depth_scale_override > 0 ? depth_scale_override : (scale_note > 0 ? scale_note : 5000.0);

  // Nearest colour image per depth frame (both lists are sorted).
  size_t j = 0;
  for (double t : f.depth_timestamps_s) {
    if (f.rgb_timestamps_s.empty()) {
      f.rgb_for_depth.push_back(-1);
      continue;
    }
    while (j + 1 < f.rgb_timestamps_s.size() &&
           std::fabs(f.rgb_timestamps_s[j + 1] - t) <= std::fabs(f.rgb_timestamps_s[j] - t)) {
      ++j;
    }
    f.rgb_for_depth.push_back(static_cast<int>(j));
  }

  // Frame rate from the median step.
  if (f.depth_timestamps_s.size() > 1) {
    std::vector<double> steps;
    for (size_t i = 1; i < f.depth_timestamps_s.size(); ++i) {
      steps.push_back(f.depth_timestamps_s[i] - f.depth_timestamps_s[i - 1]);
    }
    std::nth_element(steps.begin(), steps.begin() + static_cast<long>(steps.size() / 2),
                     steps.end());
    const double step = steps[steps.size() / 2];
    if (step > 0) f.fps = std::max(1, static_cast<int>(std::lround(1.0 / step)));
  }

  std::vector<uint16_t> depth;
  if (!readDepthPng(f.depth_files[0], &depth, &f.depth_width, &f.depth_height, error)) {
    return false;
  }
  if (!f.rgb_files.empty()) {
    std::vector<uint8_t> rgb;
    if (!readColorRgb(f.rgb_files[0], &rgb, &f.color_width, &f.color_height, error)) {
      return false;
    }
  }

  const std::string calib_path = joinPath(dir, "calibration.txt");
  std::ifstream calib(calib_path);
  if (!calib) {
    // Not guessed (a TUM default would be wrong for any other camera or resolution).
    *error = calib_path +
             ": missing; the device reports its intrinsics from it: write `fx fy cx "
             "cy width height` (pixels, depth camera)";
    return false;
  }
  {
    double fx = 0, fy = 0, cx = 0, cy = 0;
    if (!(calib >> fx >> fy >> cx >> cy) || fx <= 0 || fy <= 0) {
      *error = calib_path +
               ":1: expected `fx fy cx cy [width height]` with positive focal "
               "lengths";
      return false;
    }
    int w = 0, h = 0;
    if (calib >> w >> h && w > 0 && h > 0 && (w != f.depth_width || h != f.depth_height)) {
      // Calibration given for another resolution: scale it to the depth images.
      const double sx = static_cast<double>(f.depth_width) / w;
      const double sy = static_cast<double>(f.depth_height) / h;
      fx *= sx;
      fy *= sy;
      cx = (cx + 0.5) * sx - 0.5;
      cy = (cy + 0.5) * sy - 0.5;
    }
    f.fx = fx;
    f.fy = fy;
    f.cx = cx;
    f.cy = cy;
  }
  *out = std::move(f);
  return true;
}

}  // namespace emf::fw::virtual_device
