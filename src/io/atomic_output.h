// Atomic file output: everything emf writes (trajectories, KLG logs, eval.json, plots) goes to a
// temporary file in the destination folder and is renamed over the destination only when
// complete, so a crash or an error never leaves a half-written file under the final name.
#pragma once

#include <cstddef>
#include <cstdio>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace emf::io {

/// Writes `bytes` to `path` atomically (temp file in the same folder + fsync + rename).
/// Throws IoError naming the path and the system error.
void writeFileAtomically(const std::string& path, const std::string& bytes);
/// The same for `size` bytes at `data`.
void writeFileAtomically(const std::string& path, const void* data, size_t size);

/// Encodes `image` with OpenCV (format from the extension, e.g. .png) and writes it atomically.
/// Throws IoError if the name has no extension or the image cannot be encoded in that format.
void writeImageAtomically(const std::string& path, const cv::Mat& image,
                          const std::vector<int>& params = {});

/// A file being written atomically by streaming. Data goes to `<path>.tmp-<pid>-<n>`; commit()
/// flushes, fsyncs and renames it to `path`. Destroying it without commit() removes the
/// temporary file and leaves any existing `path` untouched.
class AtomicOutputFile {
 public:
  explicit AtomicOutputFile(std::string path);
  ~AtomicOutputFile();
  AtomicOutputFile(const AtomicOutputFile&) = delete;
  AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

  /// Appends `size` bytes. Throws IoError on a write error (disk full...).
  void write(const void* data, size_t size);
  /// Overwrites `size` bytes at absolute byte `offset` (used to patch headers such as a frame
  /// count), then returns to the end of the file.
  void writeAt(long offset, const void* data, size_t size);
  /// Bytes written so far (the current end of the file).
  long size() const;
  /// Makes the file visible under its final name. Throws IoError; no-op if already committed.
  void commit();

  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::string temp_path_;
  FILE* file_ = nullptr;
  bool committed_ = false;
};

}  // namespace emf::io
