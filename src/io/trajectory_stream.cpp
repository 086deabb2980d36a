#include "io/trajectory_stream.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "common/error.h"
#include "io/trajectory.h"

namespace emf::io {

TrajectoryStream::TrajectoryStream(std::string path, const std::string& comment)
    : path_(std::move(path)) {
  fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) {
    throw IoError("cannot create '" + path_ + "': " + std::strerror(errno) +
                  "; check that the folder exists and is writable");
  }
  writeText(tumHeader(comment));
}

TrajectoryStream::~TrajectoryStream() {
  if (fd_ >= 0) ::close(fd_);
}

void TrajectoryStream::writeText(const std::string& text) {
  size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd_, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = n < 0 ? errno : ENOSPC;
      // Cut a partly written line: the file keeps only whole poses.
      if (::ftruncate(fd_, bytes_) != 0 || ::lseek(fd_, bytes_, SEEK_SET) < 0) {
        throw IoError("cannot write '" + path_ + "': " + std::strerror(err) +
                      "; its last line may be incomplete");
      }
      throw IoError("cannot write '" + path_ + "': " + std::strerror(err) +
                    " (disk full or file size limit?)");
    }
    done += static_cast<size_t>(n);
  }
  bytes_ += static_cast<long long>(text.size());
}

bool TrajectoryStream::append(double stamp, const Eigen::Isometry3d& pose) {
  if (size_ > 0 && !(stamp > last_stamp_)) return false;
  writeText(tumLine(stamp, pose));
  last_stamp_ = stamp;
  ++size_;
  return true;
}

void TrajectoryStream::sync() {
  if (::fdatasync(fd_) != 0) {
    throw IoError("cannot sync '" + path_ + "' to disk: " + std::strerror(errno));
  }
}

}  // namespace emf::io
