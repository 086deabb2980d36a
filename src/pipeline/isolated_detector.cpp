#include "pipeline/isolated_detector.h"

#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <thread>

#include "common/error.h"
#include "common/log.h"
#include "pipeline/detector_ipc.h"
#include "pipeline/plugin_search_path.h"

extern char** environ;

namespace emf::pipeline {
namespace {

// Parent-side copies of the child's descriptors live above the usual range, so the dup2s to
// the fixed child numbers (3, 4) never overwrite one another.
constexpr int kHighFd = 100;
// How long the destructor lets the child end by itself after its socket closed.
constexpr double kExitGraceS = 2.0;

std::string signalName(int sig) {
  switch (sig) {
    case SIGSEGV:
      return "SIGSEGV";
    case SIGABRT:
      return "SIGABRT";
    case SIGBUS:
      return "SIGBUS";
    case SIGFPE:
      return "SIGFPE";
    case SIGILL:
      return "SIGILL";
    case SIGKILL:
      return "SIGKILL";
    case SIGTERM:
      return "SIGTERM";
    default:
      return "signal " + std::to_string(sig);
  }
}

std::string describeStatus(int status) {
  if (WIFSIGNALED(status)) return "killed by " + signalName(WTERMSIG(status));
  if (WIFEXITED(status)) return "exit code " + std::to_string(WEXITSTATUS(status));
  return "status " + std::to_string(status);
}

std::string secondsText(double s) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f s", s);
  return text;
}

void copyRows(const cv::Mat& src, void* dst) {
  const size_t row = src.cols * src.elemSize();
  for (int y = 0; y < src.rows; ++y) {
    std::memcpy(static_cast<char*>(dst) + y * row, src.ptr(y), row);
  }
}

}  // namespace

std::string detectorHostPath() {
  if (const char* env = std::getenv("EMF_DETECTOR_HOST"); env && *env) return env;
  std::string searched;
  for (const std::string& folder : modulePluginFolders()) {
    const std::string p = folder + "/emf_detector_host";
    if (::access(p.c_str(), X_OK) == 0) return p;
    searched += "\n  " + folder;
  }
  throw PluginError(
      "detector.isolation: process needs emf_detector_host, which is not in:" + searched +
          "\n(install emf completely, set EMF_DETECTOR_HOST, or set "
          "detector.isolation: none)",
      EMF_ERROR_NOT_FOUND);
}

IsolatedDetector::IsolatedDetector(std::string host_path, std::string plugin_path,
                                   std::string config, std::string source_uri,
                                   const core::Intrinsics& intrinsics, double deadline_s,
                                   double load_timeout_s, int nice)
    : host_path_(std::move(host_path)),
      plugin_path_(std::move(plugin_path)),
      config_(std::move(config)),
      source_uri_(std::move(source_uri)),
      intrinsics_(intrinsics),
      deadline_s_(deadline_s),
      nice_(std::to_string(nice)) {
  name_ = std::filesystem::path(plugin_path_).stem().string();
  shm_fd_ = ::memfd_create("emf-detector", MFD_CLOEXEC);
  if (shm_fd_ < 0) {
    throw PluginError(
        std::string("detector isolation: memfd_create failed: ") + std::strerror(errno),
        EMF_ERROR_IO);
  }
  ipc::Header probe{};
  ensureSegment(
      ipc::layout(probe, intrinsics.width, intrinsics.height, intrinsics.width, intrinsics.height));
  emf_status status = EMF_OK;
  const std::string error = spawn(load_timeout_s, &status);
  if (!error.empty()) {
    closeChannel();
    if (segment_) ::munmap(segment_, segment_bytes_);
    ::close(shm_fd_);
    throw PluginError(error, status);
  }
}

IsolatedDetector::~IsolatedDetector() {
  if (pid_ > 0) {
    closeChannel();  // the child's recv() returns 0: it destroys the plugin and exits
    const auto t0 = Clock::now();
    int status = 0;
    while (::waitpid(pid_, &status, WNOHANG) == 0) {
      if (std::chrono::duration<double>(Clock::now() - t0).count() > kExitGraceS) {
        ::kill(pid_, SIGKILL);
        ::waitpid(pid_, &status, 0);
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  closeChannel();
  if (segment_) ::munmap(segment_, segment_bytes_);
  if (shm_fd_ >= 0) ::close(shm_fd_);
}

void IsolatedDetector::ensureSegment(uint64_t bytes) {
  if (segment_ && bytes <= segment_bytes_) return;
  if (::ftruncate(shm_fd_, static_cast<off_t>(bytes)) != 0) {
    throw IoError(std::string("detector isolation: cannot size the shared memory: ") +
                  std::strerror(errno));
  }
  void* mapped = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_SHARED, shm_fd_, 0);
  if (mapped == MAP_FAILED) {
    throw IoError(std::string("detector isolation: cannot map the shared memory: ") +
                  std::strerror(errno));
  }
  if (segment_) ::munmap(segment_, segment_bytes_);
  segment_ = mapped;
  segment_bytes_ = bytes;
  auto* h = static_cast<ipc::Header*>(segment_);
  h->magic = ipc::kMagic;
  h->segment_bytes = segment_bytes_;
}

void IsolatedDetector::closeChannel() {
  if (socket_fd_ >= 0) ::close(socket_fd_);
  socket_fd_ = -1;
}

std::string IsolatedDetector::spawn(double timeout_s, emf_status* status) {
  *status = EMF_ERROR_IO;
  int sv[2];
  if (::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, sv) != 0) {
    return std::string("detector isolation: socketpair failed: ") + std::strerror(errno);
  }
  const int child_shm = ::fcntl(shm_fd_, F_DUPFD_CLOEXEC, kHighFd);
  const int child_sock = ::fcntl(sv[1], F_DUPFD_CLOEXEC, kHighFd);
  ::close(sv[1]);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, child_shm, ipc::kChildShmFd);
  posix_spawn_file_actions_adddup2(&actions, child_sock, ipc::kChildSocketFd);
  const std::string k[] = {std::to_string(intrinsics_.fx),    std::to_string(intrinsics_.fy),
                           std::to_string(intrinsics_.cx),    std::to_string(intrinsics_.cy),
                           std::to_string(intrinsics_.width), std::to_string(intrinsics_.height)};
  std::vector<char*> argv;
  for (const std::string* s : {&host_path_, &plugin_path_, &config_, &source_uri_}) {
    argv.push_back(const_cast<char*>(s->c_str()));
  }
  for (const std::string& s : k) argv.push_back(const_cast<char*>(s.c_str()));
  argv.push_back(const_cast<char*>(nice_.c_str()));
  argv.push_back(nullptr);
  pid_t pid = -1;
  const int rc = ::posix_spawn(&pid, host_path_.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(child_shm);
  ::close(child_sock);
  if (rc != 0) {
    ::close(sv[0]);
    return "detector isolation: cannot start '" + host_path_ + "': " + std::strerror(rc);
  }
  pid_ = pid;
  socket_fd_ = sv[0];
  ipc::Message m{};
  bool eof = false;
  if (!receive(timeout_s, &m, &eof)) {
    const std::string how = eof ? reap(false) : (reap(true) + " after " + secondsText(timeout_s));
    return "detector plugin '" + plugin_path_ + "': its host process ended while loading it (" +
           how + ")";
  }
  auto* h = static_cast<ipc::Header*>(segment_);
  if (m.op == ipc::Op::kLoadFailed) {
    *status = static_cast<emf_status>(h->load_status);
    const std::string error(h->error, strnlen(h->error, sizeof(h->error)));
    reap(false);
    return error;
  }
  if (m.op != ipc::Op::kReady) {
    reap(true);
    return "detector isolation: unexpected message from '" + host_path_ + "'";
  }
  name_ = std::string(h->plugin_name, strnlen(h->plugin_name, sizeof(h->plugin_name)));
  new_objects_only_ = h->new_objects_only != 0;
  reads_feedback_ = h->reads_feedback != 0;
  down_reason_.clear();
  return "";
}

bool IsolatedDetector::receive(double timeout_s, void* message, bool* eof) {
  *eof = false;
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(timeout_s));
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) return false;
    pollfd p{socket_fd_, POLLIN, 0};
    const int n = ::poll(&p, 1, static_cast<int>(left));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      *eof = true;
      return false;
    }
    if (n == 0) return false;
    const ssize_t got = ::recv(socket_fd_, message, sizeof(ipc::Message), 0);
    if (got == static_cast<ssize_t>(sizeof(ipc::Message))) return true;
    if (got < 0 && errno == EINTR) continue;
    *eof = true;  // 0: the child closed its end (it died); < 0: the socket broke
    return false;
  }
}

std::string IsolatedDetector::reap(bool kill_first) {
  closeChannel();
  if (pid_ <= 0) return "not running";
  if (kill_first) ::kill(pid_, SIGKILL);
  int status = 0;
  pid_t r;
  do {
    r = ::waitpid(pid_, &status, 0);
  } while (r < 0 && errno == EINTR);
  pid_ = -1;
  return r < 0 ? "not found" : describeStatus(status);
}

DetectorOutput IsolatedDetector::detect(const core::Frame& frame,
                                        const cv::Mat* background_association,
                                        const cv::Mat* residual) {
  DetectorOutput out;
  out.new_objects_only = new_objects_only_;
  const std::string who = "detector '" + name_ + "' frame " + std::to_string(frame.index);
  const auto scheduleRestart = [&](const std::string& reason) {
    down_reason_ = reason;
    restart_at_ = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                     std::chrono::duration<double>(backoff_s_));
    out.error = who + ": the detector process " + reason +
                "; the SLAM continues without detections; restarting it in " +
                secondsText(backoff_s_);
    backoff_s_ = std::min(kMaxRestartS, 2.0 * backoff_s_);
  };
  if (pid_ <= 0) {
    const double wait_s = std::chrono::duration<double>(restart_at_ - Clock::now()).count();
    if (wait_s > 0) {
      out.error = who + ": the detector process is down (" + down_reason_ + "); restarting it in " +
                  secondsText(wait_s);
      return out;
    }
    emf_status status = EMF_OK;
    const std::string error = spawn(std::max(deadline_s_, 10.0), &status);
    if (!error.empty()) {
      scheduleRestart("could not be restarted (" + error + ")");
      return out;
    }
    ++counters_.restarts;
    logInfo("detector '", name_, "': its process was restarted (pid ", pid_, ")");
  }
  if (frame.depth.type() != CV_32F || (!frame.color.empty() && frame.color.type() != CV_8UC3)) {
    out.error = who + ": frame images of the wrong type (depth CV_32F, colour CV_8UC3)";
    return out;
  }
  ipc::Header request{};
  const int w = frame.depth.cols, h = frame.depth.rows;
  const int cw = frame.color.empty() ? 0 : frame.color.cols;
  const int ch = frame.color.empty() ? 0 : frame.color.rows;
  try {
    ensureSegment(ipc::layout(request, w, h, cw, ch));
  } catch (const std::exception& e) {
    out.error = who + ": " + e.what();
    return out;
  }
  auto* hdr = static_cast<ipc::Header*>(segment_);
  char* base = static_cast<char*>(segment_);
  hdr->frame_index = frame.index;
  hdr->timestamp = frame.timestamp;
  hdr->rgb_timestamp = frame.rgb_timestamp;
  const size_t stamp = std::min(frame.timestamp_text.size(), sizeof(hdr->timestamp_text) - 1);
  std::memcpy(hdr->timestamp_text, frame.timestamp_text.data(), stamp);
  hdr->timestamp_text[stamp] = '\0';
  hdr->width = w;
  hdr->height = h;
  hdr->color_width = cw;
  hdr->color_height = ch;
  hdr->depth_offset = request.depth_offset;
  hdr->color_offset = request.color_offset;
  hdr->association_offset = request.association_offset;
  hdr->residual_offset = request.residual_offset;
  hdr->masks_offset = request.masks_offset;
  copyRows(frame.depth, base + hdr->depth_offset);
  if (cw > 0) copyRows(frame.color, base + hdr->color_offset);
  const auto feedback = [&](const cv::Mat* m, uint64_t offset) {
    if (!m || m->empty() || m->type() != CV_32F || m->cols != w || m->rows != h) return 0;
    copyRows(*m, base + offset);
    return 1;
  };
  hdr->has_background_association = feedback(background_association, hdr->association_offset);
  hdr->has_residual = feedback(residual, hdr->residual_offset);
  hdr->count = 0;
  hdr->rejected_count = 0;
  hdr->error[0] = '\0';

  const ipc::Message m{ipc::Op::kDetect, 0, ++seq_};
  ipc::Message reply{};
  bool eof = false;
  const bool sent = ::send(socket_fd_, &m, sizeof(m), MSG_NOSIGNAL) == sizeof(m);
  if (!sent || !receive(deadline_s_, &reply, &eof) || reply.op != ipc::Op::kDone ||
      reply.seq != m.seq) {
    if (!sent || eof) {
      ++counters_.crashes;
      scheduleRestart("crashed (" + reap(false) + ")");
    } else {
      ++counters_.timeouts;
      reap(true);
      scheduleRestart("gave no result within detector.deadline_s (" + secondsText(deadline_s_) +
                      ") and was killed");
    }
    logWarning(out.error);
    return out;
  }
  backoff_s_ = kFirstRestartS;
  out.new_objects_only = hdr->response_new_objects_only != 0;
  out.error = std::string(hdr->error, strnlen(hdr->error, sizeof(hdr->error)));
  const int count = std::clamp(hdr->count, 0, ipc::kMaxDetections);
  const size_t mask_floats = static_cast<size_t>(w) * h;
  for (int i = 0; i < count; ++i) {
    const ipc::DetectionRecord& r = hdr->detections[i];
    core::Detection d;
    d.id = r.id;
    d.score = r.score;
    d.box = cv::Rect(r.box_x, r.box_y, r.box_width, r.box_height);
    d.class_name = std::string(r.class_name, strnlen(r.class_name, sizeof(r.class_name)));
    d.mask =
        cv::Mat(h, w, CV_32F,
                base + hdr->masks_offset + static_cast<size_t>(i) * mask_floats * sizeof(float))
            .clone();
    out.detections.push_back(std::move(d));
  }
  const int rejected = std::max(0, hdr->rejected_count);
  for (int i = 0; i < rejected; ++i) {
    out.rejected.push_back(
        i < ipc::kRejectedKept
            ? std::string(hdr->rejected[i], strnlen(hdr->rejected[i], sizeof(hdr->rejected[i])))
            : who + ": a detection beyond the " + std::to_string(ipc::kRejectedKept) +
                  " whose messages cross the process boundary was dropped");
  }
  return out;
}

}  // namespace emf::pipeline
