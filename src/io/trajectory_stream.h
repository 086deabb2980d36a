// A TUM trajectory written as the run goes: each pose is appended under the file's final name
// with one write(2), so a killed process leaves every pose appended before the kill; sync() also
// asks the disk to keep them (a power cut loses only what came after the last sync). The file is
// readable by readTrajectory at any moment: a write that fails half-way (disk full, file size
// limit) is cut back to the last whole line, and one cut short by a SIGKILL (the kernel may
// stop a write between two pages) leaves an unfinished last line that readTrajectory ignores.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <string>

namespace emf::io {

class TrajectoryStream {
 public:
  /// Creates (or truncates) `path` and writes the header (tumHeader(comment)). Throws IoError
  /// naming the path and the system error.
  TrajectoryStream(std::string path, const std::string& comment);
  ~TrajectoryStream();
  TrajectoryStream(const TrajectoryStream&) = delete;
  TrajectoryStream& operator=(const TrajectoryStream&) = delete;

  /// Appends one pose and flushes it. A `stamp` (seconds) not after the last one appended is
  /// not written (TUM files need increasing stamps): returns false. Throws IoError on a write
  /// error (disk full, file size limit), naming the path.
  bool append(double stamp, const Eigen::Isometry3d& pose);
  /// fdatasync: the poses appended so far survive a power cut. Throws IoError.
  void sync();

  const std::string& path() const { return path_; }
  size_t size() const { return size_; }
  /// Timestamp of the last pose appended (seconds; undefined when size() == 0).
  double lastStamp() const { return last_stamp_; }

 private:
  void writeText(const std::string& text);

  std::string path_;
  int fd_ = -1;
  long long bytes_ = 0;  // length of the whole lines written
  size_t size_ = 0;
  double last_stamp_ = 0;
};

}  // namespace emf::io
