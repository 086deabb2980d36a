// emf_detector_host: runs one detector plugin in its own process for emf (detector.isolation:
// process), so a plugin that crashes, aborts or hangs takes only this process down. Started by
// pipeline::IsolatedDetector with the shared memory segment on fd 3 and its socket on fd 4
// (pipeline/detector_ipc.h); not meant to be run by hand.
//
//   emf_detector_host <plugin.so> <config> <source uri> <fx> <fy> <cx> <cy> <width> <height>
//                     <nice>   (detector.nice: set before the plugin loads)
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "common/status_name.h"
#include "pipeline/detector_ipc.h"
#include "pipeline/detector_plugin.h"

namespace {

using emf::pipeline::ipc::Header;
using emf::pipeline::ipc::Message;
using emf::pipeline::ipc::Op;
namespace ipc = emf::pipeline::ipc;

void copyText(char* dst, size_t capacity, const std::string& text) {
  const size_t n = std::min(capacity - 1, text.size());
  std::memcpy(dst, text.data(), n);
  dst[n] = '\0';
}

bool send(Op op, int64_t seq) {
  const Message m{op, 0, seq};
  return ::send(ipc::kChildSocketFd, &m, sizeof(m), MSG_NOSIGNAL) == sizeof(m);
}

// The segment, remapped when the parent grew it.
struct Segment {
  void* base = MAP_FAILED;
  size_t bytes = 0;
  bool map() {
    struct stat st {};
    if (::fstat(ipc::kChildShmFd, &st) != 0) return false;
    const size_t want = static_cast<size_t>(st.st_size);
    if (base != MAP_FAILED && want == bytes) return true;
    if (base != MAP_FAILED) ::munmap(base, bytes);
    base = ::mmap(nullptr, want, PROT_READ | PROT_WRITE, MAP_SHARED, ipc::kChildShmFd, 0);
    bytes = want;
    return base != MAP_FAILED;
  }
  Header& header() const { return *static_cast<Header*>(base); }
  char* at(uint64_t offset) const { return static_cast<char*>(base) + offset; }
};

void respond(Segment& seg, emf::pipeline::DetectorPlugin& plugin) {
  Header& h = seg.header();
  emf::core::Frame frame;
  frame.index = h.frame_index;
  frame.timestamp = h.timestamp;
  frame.rgb_timestamp = h.rgb_timestamp;
  frame.timestamp_text =
      std::string(h.timestamp_text, strnlen(h.timestamp_text, sizeof(h.timestamp_text)));
  // Views of the segment: no copy.
  frame.depth = cv::Mat(h.height, h.width, CV_32F, seg.at(h.depth_offset));
  if (h.color_width > 0 && h.color_height > 0) {
    frame.color = cv::Mat(h.color_height, h.color_width, CV_8UC3, seg.at(h.color_offset));
  }
  const cv::Mat association(h.height, h.width, CV_32F, seg.at(h.association_offset));
  const cv::Mat residual(h.height, h.width, CV_32F, seg.at(h.residual_offset));
  const emf::pipeline::DetectorOutput out =
      plugin.detect(frame, h.has_background_association ? &association : nullptr,
                    h.has_residual ? &residual : nullptr);
  copyText(h.error, sizeof(h.error), out.error);
  h.response_new_objects_only = out.new_objects_only ? 1 : 0;
  h.rejected_count = static_cast<int32_t>(out.rejected.size());
  for (int i = 0; i < ipc::kRejectedKept && i < h.rejected_count; ++i) {
    copyText(h.rejected[i], sizeof(h.rejected[i]), out.rejected[static_cast<size_t>(i)]);
  }
  const size_t mask_bytes = static_cast<size_t>(h.width) * h.height * sizeof(float);
  int count = 0;
  for (const emf::core::Detection& d : out.detections) {
    if (count == ipc::kMaxDetections) {
      ++h.rejected_count;  // the parent names the limit
      continue;
    }
    ipc::DetectionRecord& r = h.detections[count];
    r.id = d.id;
    r.score = d.score;
    r.box_x = d.box.x;
    r.box_y = d.box.y;
    r.box_width = d.box.width;
    r.box_height = d.box.height;
    copyText(r.class_name, sizeof(r.class_name), d.class_name);
    cv::Mat dst(h.height, h.width, CV_32F, seg.at(h.masks_offset + count * mask_bytes));
    d.mask.copyTo(dst);
    ++count;
  }
  h.count = count;
}

}  // namespace

int main(int argc, char** argv) {
  // Ends with emf: a parent killed without a word must not leave this process behind.
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (argc != 11) {
    std::fprintf(stderr,
                 "emf_detector_host: started by emf for detector.isolation: process; not meant "
                 "to be run by hand\n");
    return 2;
  }
  Segment seg;
  if (!seg.map() || seg.header().magic != ipc::kMagic) {
    std::fprintf(stderr, "emf_detector_host: no shared memory segment on fd %d\n",
                 ipc::kChildShmFd);
    return 2;
  }
  // detector.nice, before the plugin starts any thread (its threads inherit it).
  const int nice = std::atoi(argv[10]);
  if (nice > 0 && ::setpriority(PRIO_PROCESS, 0, nice) != 0) {
    std::fprintf(stderr, "emf_detector_host: cannot set niceness %d: %s\n", nice,
                 std::strerror(errno));
  }
  emf::core::Intrinsics k;
  k.fx = std::atof(argv[4]);
  k.fy = std::atof(argv[5]);
  k.cx = std::atof(argv[6]);
  k.cy = std::atof(argv[7]);
  k.width = std::atoi(argv[8]);
  k.height = std::atoi(argv[9]);
  std::unique_ptr<emf::pipeline::DetectorPlugin> plugin;
  try {
    plugin = emf::pipeline::DetectorPlugin::load(argv[1], {}, argv[2], argv[3], k);
  } catch (const emf::pipeline::PluginError& e) {
    copyText(seg.header().error, sizeof(seg.header().error), e.what());
    seg.header().load_status = e.status();
    send(Op::kLoadFailed, 0);
    return 1;
  } catch (const std::exception& e) {
    copyText(seg.header().error, sizeof(seg.header().error), e.what());
    seg.header().load_status = EMF_ERROR_INTERNAL;
    send(Op::kLoadFailed, 0);
    return 1;
  }
  plugin->setLogProblems(false);  // the parent's scheduler logs once per kind
  Header& h = seg.header();
  h.new_objects_only = plugin->newObjectsOnly() ? 1 : 0;
  h.reads_feedback = plugin->readsFeedback() ? 1 : 0;
  copyText(h.plugin_name, sizeof(h.plugin_name), plugin->name());
  if (!send(Op::kReady, 0)) return 1;
  for (;;) {
    Message m{};
    const ssize_t n = ::recv(ipc::kChildSocketFd, &m, sizeof(m), 0);
    if (n <= 0) return 0;  // the parent closed the socket: done
    if (n != sizeof(m) || m.op != Op::kDetect) continue;
    if (!seg.map()) return 1;
    try {
      respond(seg, *plugin);
    } catch (const std::exception& e) {
      copyText(seg.header().error, sizeof(seg.header().error),
               std::string("detector host: ") + e.what());
      seg.header().count = 0;
    }
    if (!send(Op::kDone, m.seq)) return 1;
  }
}
