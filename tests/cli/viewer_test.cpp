// `emf run --view / --video / --frames-png`: the pictures of a run. The overlay colour of each
// object lies on its ground-truth mask of the synthetic scene; the video holds one decodable
// frame per processed frame; the window, on a virtual X server (Xvfb), shows those pictures.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <thread>

#include "core/frame_source.h"
#include "pipeline/object_outputs.h"
#include "sources/open_source.h"
#include "test_support.h"

namespace emf {
namespace {

namespace fs = std::filesystem;
const std::string kCli = EMF_CLI_PATH;
// A pixel counts as "object id's overlay colour" when each channel is within this of
// (1 - kOverlayAlpha) * colour + kOverlayAlpha * objectColor(id) (rounding, PNG is lossless).
constexpr int kColourTolerance = 2;
// Share of a ground-truth mask (eroded by 2 px: edges are where depth and model disagree, and
// labels cover part of it) that must carry one object's overlay colour.
constexpr double kMinMaskCoverage = 0.6;
constexpr int kMinMaskPixels = 300;
// Mean squared difference per channel (8-bit levels) between the screen and a written picture.
// Consecutive frames of the room scene differ by about 180; a repaint caught half-way by < 0.1.
constexpr double kMaxScreenDifference = 1.0;

const std::string kSmall =
    " --quiet --set map.memory_mb=64 --set map.background_voxel_m=0.02"
    " --set map.background_resolution=256";

TEST(Viewer, TheOverlayColourOfEachCarLiesOnItsGroundTruthMask) {
  const std::string dir = test::tempDir("viewer-gt");
  const std::string uri = "synth:cars?frames=36&width=320&height=240";
  std::string out;
  ASSERT_EQ(
      test::runCommand(
          kCli + " synth cars --frames 36 --width 320 --height 240 --out " + dir + "/seq", &out),
      0)
      << out;
  ASSERT_EQ(test::runCommand(kCli + " run" + kSmall + " --source tum:" + dir +
                                 "/seq --detector maskfile --frames-png " + dir + "/png --out " +
                                 dir + "/run",
                             &out),
            0)
      << out;
  // The same scene straight from the renderer: the ground-truth instance ids of frame 35.
  auto src = sources::openSource(uri, core::SourceOptions());
  core::Frame f;
  for (int i = 0; i <= 35; ++i) ASSERT_TRUE(src->next(f));
  ASSERT_EQ(f.instance_ids.type(), CV_16U);
  const cv::Mat panel = cv::imread(dir + "/png/000035.png", cv::IMREAD_COLOR);
  ASSERT_EQ(panel.size(), cv::Size(480, 360));
  const cv::Mat overlay = panel(cv::Rect(0, 0, 320, 240));
  double min, max;
  cv::minMaxLoc(f.instance_ids, &min, &max);
  int checked = 0;
  for (int k = 1; k <= static_cast<int>(max); ++k) {
    cv::Mat mask = f.instance_ids == k;
    cv::erode(mask, mask, cv::Mat(), cv::Point(-1, -1), 2);
    const int pixels = cv::countNonZero(mask);
    if (pixels < kMinMaskPixels) continue;
    std::array<int, 9> votes{};
    for (int y = 0; y < mask.rows; ++y) {
      for (int x = 0; x < mask.cols; ++x) {
        if (!mask.at<uint8_t>(y, x)) continue;
        const cv::Vec3b c = f.color.at<cv::Vec3b>(y, x), p = overlay.at<cv::Vec3b>(y, x);
        for (int id = 1; id < 9; ++id) {
          const cv::Vec3b o = pipeline::objectColor(id);
          bool match = true;
          for (int ch = 0; ch < 3; ++ch) {
            const double want =
                (1 - pipeline::kOverlayAlpha) * c[ch] + pipeline::kOverlayAlpha * o[ch];
            match = match && std::abs(p[ch] - want) <= kColourTolerance;
          }
          votes[id] += match;
        }
      }
    }
    const int best = static_cast<int>(std::max_element(votes.begin(), votes.end()) - votes.begin());
    EXPECT_GE(votes[best], kMinMaskCoverage * pixels)
        << "ground-truth object " << k << ": " << votes[best] << " of " << pixels
        << " mask pixels carry object " << best << "'s overlay colour";
    ++checked;
  }
  EXPECT_EQ(checked, 2);  // both cars in view at frame 35
}

TEST(Viewer, TheVideoHasOneDecodableFramePerProcessedFrame) {
  const std::string dir = test::tempDir("viewer-video");
  std::string out;
  ASSERT_EQ(test::runCommand(kCli + " run" + kSmall +
                                 " --source 'synth:room?frames=12&width=160&height=120' --video " +
                                 dir + "/run.avi --out " + dir + "/run",
                             &out),
            0)
      << out;
  EXPECT_NE(out.find("12 written"), std::string::npos) << out;
  cv::VideoCapture video(dir + "/run.avi");
  ASSERT_TRUE(video.isOpened());
  int frames = 0;
  cv::Mat picture;
  while (video.read(picture)) {
    EXPECT_EQ(picture.size(), cv::Size(240, 180));
    ++frames;
  }
  EXPECT_EQ(frames, 12);
  // A name OpenCV cannot pick a container for is refused before the first frame.
  EXPECT_EQ(test::runCommand(kCli + " run" + kSmall +
                                 " --source 'synth:room?frames=2&width=160&height=120' --video " +
                                 dir + "/run.mkv --out " + dir + "/run2",
                             &out),
            1);
  EXPECT_NE(out.find("must end in .avi (Motion JPEG) or .mp4"), std::string::npos) << out;
}

TEST(Viewer, WithoutADisplayTheWindowIsAClearError) {
  std::string out;
  const std::string dir = test::tempDir("viewer-nodisplay");
  EXPECT_EQ(test::runCommand("env -u DISPLAY -u WAYLAND_DISPLAY " + kCli + " run" + kSmall +
                                 " --source 'synth:room?frames=2&width=160&height=120' --view "
                                 "--out " +
                                 dir,
                             &out),
            1);
  EXPECT_NE(out.find("--view needs a display ($DISPLAY is not set"), std::string::npos) << out;
  // A display nobody serves: refused before the run (the toolkit would abort in the middle).
  EXPECT_EQ(test::runCommand("DISPLAY=:987 " + kCli + " run" + kSmall +
                                 " --source 'synth:room?frames=2&width=160&height=120' --view "
                                 "--out " +
                                 dir + "/2",
                             &out),
            1);
  EXPECT_NE(out.find("--view: cannot connect to the X display ':987'"), std::string::npos) << out;
}

// An X window dump (xwd -root) as BGR: the ZPixmap of a 24-bit TrueColor root (24 or 32 bits
// per pixel).
cv::Mat readXwd(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<unsigned char> b((std::istreambuf_iterator<char>(in)), {});
  const auto u32 = [&](size_t field) {
    const size_t i = field * 4;
    return (uint32_t(b.at(i)) << 24) | (uint32_t(b.at(i + 1)) << 16) |
           (uint32_t(b.at(i + 2)) << 8) | uint32_t(b.at(i + 3));
  };
  const uint32_t header = u32(0), width = u32(4), height = u32(5), byte_order = u32(7),
                 bpp = u32(11), line = u32(12), ncolors = u32(19);
  if (bpp != 32 && bpp != 24) {
    ADD_FAILURE() << path << ": " << bpp << " bits per pixel (expected 24 or 32)";
    return cv::Mat();
  }
  const size_t step = bpp / 8;
  const size_t data = header + ncolors * 12;
  cv::Mat out(static_cast<int>(height), static_cast<int>(width), CV_8UC3);
  for (uint32_t y = 0; y < height; ++y) {
    for (uint32_t x = 0; x < width; ++x) {
      const unsigned char* p = &b.at(data + y * line + x * step);
      // LSBFirst (0): B G R [x] in memory; MSBFirst: [x] R G B.
      out.at<cv::Vec3b>(static_cast<int>(y), static_cast<int>(x)) =
          byte_order == 0 ? cv::Vec3b(p[0], p[1], p[2])
                          : cv::Vec3b(p[step - 1], p[step - 2], p[step - 3]);
    }
  }
  return out;
}

TEST(Viewer, TheWindowShowsThePicturesUnderXvfb) {
  ASSERT_EQ(test::runCommand("command -v Xvfb && command -v xwd", nullptr), 0)
      << "Xvfb and xwd are installed by scripts/install_deps.sh (xvfb, x11-apps)";
  const std::string dir = test::tempDir("viewer-xvfb");
  // A display number of our own: Xvfb picks a free one and writes it to the pipe, the digits and
  // the newline in two writes. The pipe stays open until the newline: closed after the digits,
  // the second write fails and Xvfb exits ("Cannot write display number"). A server that is
  // gone once its socket should be up is started again.
  constexpr int kXvfbStarts = 3;
  pid_t xvfb = -1;
  std::string digits;
  for (int attempt = 0; attempt < kXvfbStarts; ++attempt) {
    int fds[2];
    ASSERT_EQ(pipe(fds), 0);
    xvfb = fork();
    if (xvfb == 0) {
      close(fds[0]);
      const std::string fd = std::to_string(fds[1]);
      execlp("Xvfb", "Xvfb", "-displayfd", fd.c_str(), "-screen", "0", "1280x1024x24", "-nolisten",
             "tcp", static_cast<char*>(nullptr));
      _exit(127);
    }
    close(fds[1]);
    std::string number;
    char c = 0;
    while (number.size() < 16 && read(fds[0], &c, 1) == 1 && c != '\n') number += c;
    close(fds[0]);
    digits.clear();
    for (const char d : number) {
      if (!std::isdigit(static_cast<unsigned char>(d))) break;
      digits += d;
    }
    // Its socket must accept connections before emf starts (emf checks, then refuses).
    for (int i = 0; !digits.empty() && i < 500 && !fs::exists("/tmp/.X11-unix/X" + digits); ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    if (!digits.empty() && waitpid(xvfb, nullptr, WNOHANG) == 0) break;
    kill(xvfb, SIGTERM);
    waitpid(xvfb, nullptr, 0);
    xvfb = -1;
  }
  ASSERT_GT(xvfb, 0) << "Xvfb did not start in " << kXvfbStarts << " tries";
  const std::string display = ":" + digits;
  struct Reaper {
    pid_t pid;
    ~Reaper() {
      kill(pid, SIGTERM);
      waitpid(pid, nullptr, 0);
    }
  } reaper{xvfb};
  // A long run (the window is up while we look), its pictures also written as PNGs.
  const std::string run = kCli + " run" + kSmall +
                          " --source 'synth:room?frames=400&width=320&height=240' --view "
                          "--frames-png " +
                          dir + "/png --out " + dir + "/run";
  const pid_t emf = fork();
  if (emf == 0) {
    execl("/bin/sh", "sh", "-c",
          ("DISPLAY=" + display + " exec " + run + " >" + dir + "/log 2>&1").c_str(),
          static_cast<char*>(nullptr));
    _exit(127);
  }
  const auto t0 = std::chrono::steady_clock::now();
  bool exited = false;
  int status = 0;
  while (!fs::exists(dir + "/png/000030.png") &&
         std::chrono::steady_clock::now() - t0 < std::chrono::seconds(120)) {
    if (waitpid(emf, &status, WNOHANG) == emf) {
      exited = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_FALSE(exited) << "emf ended before its 30th picture:\n" << test::readText(dir + "/log");
  ASSERT_TRUE(fs::exists(dir + "/png/000030.png"))
      << "no 30th picture in 120 s; emf's log so far:\n"
      << test::readText(dir + "/log");
  std::string out;
  ASSERT_EQ(test::runCommand("xwd -root -silent -display " + display + " -out " + dir + "/shot.xwd",
                             &out),
            0)
      << out;
  // SIGTERM, not SIGINT: a test run as a background job has SIGINT ignored, and emf keeps that.
  kill(emf, SIGTERM);
  waitpid(emf, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 143) << test::readText(dir + "/log");
  const cv::Mat shot = readXwd(dir + "/shot.xwd");
  ASSERT_FALSE(shot.empty());
  // Somewhere on the screen (where the toolkit put the window) is one of the run's pictures:
  // the window shows what the video and the PNGs get. Nearly pixel for pixel: the screenshot
  // may catch the window while it repaints from one frame to the next (a few pixels of text).
  bool found = false;
  double closest = -1;
  for (const auto& e : fs::directory_iterator(dir + "/png")) {
    const cv::Mat png = cv::imread(e.path().string(), cv::IMREAD_COLOR);
    if (png.empty() || png.cols > shot.cols || png.rows > shot.rows) continue;
    cv::Mat diff;
    cv::matchTemplate(shot, png, diff, cv::TM_SQDIFF);
    double best = 0;
    cv::minMaxLoc(diff, &best);
    best /= static_cast<double>(png.total() * 3);  // mean squared difference per channel
    if (closest < 0 || best < closest) closest = best;
    if (best <= kMaxScreenDifference) {
      found = true;
      break;
    }
  }
  EXPECT_TRUE(found) << "the screen does not show any of the pictures written to " << dir
                     << "/png (closest: mean squared difference " << closest << ")";
}

}  // namespace
}  // namespace emf
