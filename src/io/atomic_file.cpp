#include "io/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "common/error.h"

namespace emf::io {
namespace {

std::string temporaryPath(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  return path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
}

}  // namespace

void writeFileAtomic(const std::string& path, const void* data, size_t size) {
  const std::string tmp = temporaryPath(path);
  FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) {
    throw IoError("cannot write " + path + ": " + std::strerror(errno) +
                  " (check that the folder exists and is writable)");
  }
  const size_t written = size > 0 ? std::fwrite(data, 1, size, f) : 0;
  const int write_errno = errno;
  const bool ok = written == size && std::fflush(f) == 0;
  const int flush_errno = errno;
  if (std::fclose(f) != 0 || !ok) {
    std::remove(tmp.c_str());
    throw IoError("cannot write " + path + ": " +
                  std::strerror(written != size ? write_errno : flush_errno) +
                  " (disk full or not writable?)");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    throw IoError("cannot write " + path + ": rename from " + tmp + " failed: " + ec.message());
  }
}

void writeTextAtomic(const std::string& path, const std::string& text) {
  writeFileAtomic(path, text.data(), text.size());
}

void writeImageAtomic(const std::string& path, const cv::Mat& image,
                      const std::vector<int>& params) {
  const auto dot = path.rfind('.');
  if (dot == std::string::npos || path.find('/', dot) != std::string::npos) {
    throw IoError("cannot write image " + path + ": the file name has no extension (.png, .jpg)");
  }
  std::vector<uint8_t> bytes;
  bool ok = false;
  try {
    ok = cv::imencode(path.substr(dot), image, bytes, params);
  } catch (const cv::Exception& e) {
    throw IoError("cannot encode image " + path + ": " + e.what());
  }
  if (!ok) throw IoError("cannot encode image " + path + " in format " + path.substr(dot));
  writeFileAtomic(path, bytes.data(), bytes.size());
}

}  // namespace emf::io
