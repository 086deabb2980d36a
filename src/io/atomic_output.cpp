#include "io/atomic_output.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "common/error.h"

namespace emf::io {
namespace {

std::string tempPathFor(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  return path + ".tmp-" + std::to_string(getpid()) + "-" + std::to_string(counter++);
}

std::string systemError() { return std::strerror(errno); }

}  // namespace

void writeFileAtomically(const std::string& path, const std::string& bytes) {
  writeFileAtomically(path, bytes.data(), bytes.size());
}

void writeFileAtomically(const std::string& path, const void* data, size_t size) {
  AtomicOutputFile f(path);
  f.write(data, size);
  f.commit();
}

void writeImageAtomically(const std::string& path, const cv::Mat& image,
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
  writeFileAtomically(path, bytes.data(), bytes.size());
}

AtomicOutputFile::AtomicOutputFile(std::string path)
    : path_(std::move(path)), temp_path_(tempPathFor(path_)) {
  file_ = std::fopen(temp_path_.c_str(), "wb");
  if (!file_) {
    throw IoError("cannot create '" + temp_path_ + "' (to write '" + path_ +
                  "'): " + systemError() + "; check that the folder exists and is writable");
  }
}

AtomicOutputFile::~AtomicOutputFile() {
  if (file_) std::fclose(file_);
  if (!committed_) {
    std::error_code ec;
    std::filesystem::remove(temp_path_, ec);
  }
}

void AtomicOutputFile::write(const void* data, size_t size) {
  if (!file_) throw IoError("'" + path_ + "' was already committed; cannot write more");
  if (size > 0 && std::fwrite(data, 1, size, file_) != size) {
    throw IoError("cannot write '" + temp_path_ + "': " + systemError() + " (disk full?)");
  }
}

void AtomicOutputFile::writeAt(long offset, const void* data, size_t size) {
  if (!file_) throw IoError("'" + path_ + "' was already committed; cannot write more");
  if (std::fseek(file_, offset, SEEK_SET) != 0) {
    throw IoError("cannot seek in '" + temp_path_ + "': " + systemError());
  }
  write(data, size);
  if (std::fseek(file_, 0, SEEK_END) != 0) {
    throw IoError("cannot seek in '" + temp_path_ + "': " + systemError());
  }
}

long AtomicOutputFile::size() const { return file_ ? std::ftell(file_) : -1; }

void AtomicOutputFile::commit() {
  if (committed_) return;
  if (std::fflush(file_) != 0 || fsync(fileno(file_)) != 0) {
    throw IoError("cannot flush '" + temp_path_ + "': " + systemError() + " (disk full?)");
  }
  const int rc = std::fclose(file_);
  file_ = nullptr;
  if (rc != 0) throw IoError("cannot close '" + temp_path_ + "': " + systemError());
  if (std::rename(temp_path_.c_str(), path_.c_str()) != 0) {
    const std::string err = systemError();
    std::error_code ec;
    std::filesystem::remove(temp_path_, ec);
    throw IoError("cannot rename '" + temp_path_ + "' to '" + path_ + "': " + err);
  }
  committed_ = true;
}

}  // namespace emf::io
