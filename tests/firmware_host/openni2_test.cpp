// The OpenNI2 backend end to end: the real libOpenNI2 loads the emf virtual device driver from the
// build tree's driver folder, and Openni2Source reads it (and an .oni recording OpenNI2 makes of
// it). Depth is compared exactly with the PNGs, timestamps with depth.txt, intrinsics with
// calibration.txt.
#include <OpenNI.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "common/error.h"
#include "firmware_host/openni2/openni2_source.h"
#include "firmware_host/reconnecting_source.h"
#include "firmware_host/sensor_error.h"
#include "firmware_host/sensor_sources.h"
#include "test_support.h"

namespace emf::fw {
namespace {

namespace fs = std::filesystem;

// The virtual device reports a float field of view; fx = w / (2 tan(hfov / 2)) recovers the
// calibrated focal length to float precision.
constexpr double kFovIntrinsicsTolerancePx = 0.01;

struct TumList {
  std::vector<double> stamps;
  std::vector<std::string> files;
};

TumList readList(const std::string& path) {
  TumList l;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream f(line);
    double t;
    std::string name;
    f >> t >> name;
    l.stamps.push_back(t);
    l.files.push_back(name);
  }
  return l;
}

/// Expected depth in metres, exactly as the source converts it: raw * unit, 0 -> NaN.
cv::Mat expectedDepth(const std::string& png, double unit_m) {
  const cv::Mat raw = cv::imread(png, cv::IMREAD_UNCHANGED);
  EXPECT_EQ(raw.type(), CV_16UC1) << png;
  cv::Mat out(raw.size(), CV_32FC1);
  for (int y = 0; y < raw.rows; ++y) {
    for (int x = 0; x < raw.cols; ++x) {
      const uint16_t v = raw.at<uint16_t>(y, x);
      out.at<float>(y, x) =
          v == 0 ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(v * unit_m);
    }
  }
  return out;
}

/// Number of pixels that differ (NaN == NaN).
int depthMismatches(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) return -1;
  int bad = 0;
  for (int y = 0; y < a.rows; ++y) {
    for (int x = 0; x < a.cols; ++x) {
      const float u = a.at<float>(y, x), v = b.at<float>(y, x);
      if (!(u == v || (std::isnan(u) && std::isnan(v)))) ++bad;
    }
  }
  return bad;
}

std::string kitchen() { return test::dataPath("redkitchen-0-299"); }

/// A tiny TUM folder: `n` frames of 64x48, TUM depth scale 5000, absolute timestamps at 10 Hz.
std::string makeTinyFolder(int n) {
  const std::string dir = test::tempDir("tiny-tum");
  fs::create_directories(dir + "/depth");
  fs::create_directories(dir + "/rgb");
  std::ofstream d(dir + "/depth.txt"), r(dir + "/rgb.txt"), c(dir + "/calibration.txt");
  d << "# depth maps\n# timestamp filename\n";
  r << "# color images\n";
  c << "50 52 31.5 23.5 64 48\n";
  for (int i = 0; i < n; ++i) {
    cv::Mat depth(48, 64, CV_16UC1);
    for (int y = 0; y < 48; ++y) {
      for (int x = 0; x < 64; ++x) {
        depth.at<uint16_t>(y, x) =
            static_cast<uint16_t>((x + y) % 7 == 0 ? 0 : 5000 + 97 * i + x * 3 + y);
      }
    }
    cv::Mat color(48, 64, CV_8UC3, cv::Scalar(10 * i, 100, 200));
    char name[64];
    std::snprintf(name, sizeof(name), "%06d.png", i);
    cv::imwrite(dir + "/depth/" + name, depth);
    cv::imwrite(dir + "/rgb/" + name, color);
    char stamp[64];
    std::snprintf(stamp, sizeof(stamp), "%.6f", 1305031102.0 + 0.1 * i);
    d << stamp << " depth/" << name << "\n";
    r << stamp << " rgb/" << name << "\n";
  }
  return dir;
}

TEST(Openni2Virtual, DriverIsLoadedAndDevicesEnumeratedFromEnvironment) {
  const std::string uri = "emf-virtual://" + kitchen();
  ::setenv("EMF_VIRTUAL_DEVICES", uri.c_str(), 1);
  const auto devices = listOpenni2Devices();
  ::unsetenv("EMF_VIRTUAL_DEVICES");
  int found = 0;
  for (const auto& d : devices) {
    if (d.uri == uri) {
      ++found;
      EXPECT_EQ(d.vendor, "emf");
    }
  }
  EXPECT_EQ(found, 1) << "driver folder: " << openni2DriverFolder();
  EXPECT_EQ(fs::path(openni2DriverFolder()).parent_path().parent_path(),
            fs::path(EMF_TEST_BINARY_DIR) / "openni2");
}

TEST(Openni2Virtual, LosslessReplayMatchesPngsTimestampsAndIntrinsics) {
  const std::string dir = kitchen();
  const TumList depth_list = readList(dir + "/depth.txt");
  const TumList rgb_list = readList(dir + "/rgb.txt");
  core::SourceOptions options;
  Openni2Source src("openni2:emf-virtual://" + dir + ";speed=0", options);
  EXPECT_EQ(src.size(), 300);
  EXPECT_TRUE(src.isLive());
  EXPECT_FALSE(src.registered());  // the device honestly supports only registration off
  EXPECT_TRUE(src.synced());
  const core::Intrinsics k = src.intrinsics();
  EXPECT_EQ(k.width, 640);
  EXPECT_EQ(k.height, 480);
  EXPECT_NEAR(k.fx, 585.0, kFovIntrinsicsTolerancePx);
  EXPECT_NEAR(k.fy, 585.0, kFovIntrinsicsTolerancePx);
  EXPECT_EQ(k.cx, 320.0);
  EXPECT_EQ(k.cy, 240.0);
  EXPECT_NE(src.describe().find("DEPTH_1_MM"), std::string::npos) << src.describe();

  constexpr int kFrames = 12;
  for (int i = 0; i < kFrames; ++i) {
    core::Frame f;
    ASSERT_TRUE(src.next(f)) << i;
    EXPECT_EQ(f.index, i);
    EXPECT_NEAR(f.timestamp, depth_list.stamps[static_cast<size_t>(i)], 1e-6);
    EXPECT_NEAR(f.rgb_timestamp, rgb_list.stamps[static_cast<size_t>(i)], 1e-6);
    EXPECT_EQ(depthMismatches(f.depth, expectedDepth(dir + "/" + depth_list.files[i], 0.001)), 0)
        << "frame " << i;
    // Colour: the driver decodes the JPEG with libjpeg as OpenCV does; same decoder, same bytes.
    const cv::Mat bgr = cv::imread(dir + "/" + rgb_list.files[static_cast<size_t>(i)]);
    ASSERT_EQ(f.color.size(), bgr.size());
    EXPECT_EQ(cv::norm(f.color, bgr, cv::NORM_INF), 0.0) << "frame " << i;
  }
}

TEST(Openni2Virtual, RecordingEndsAfterLastFrameAnd100umDepth) {
  const std::string dir = makeTinyFolder(3);
  core::SourceOptions options;
  Openni2Source src("openni2:emf-virtual://" + dir + ";speed=0", options);
  EXPECT_EQ(src.size(), 3);
  EXPECT_NEAR(src.intrinsics().fx, 50.0, kFovIntrinsicsTolerancePx);
  EXPECT_NEAR(src.intrinsics().fy, 52.0, kFovIntrinsicsTolerancePx);
  EXPECT_NE(src.describe().find("DEPTH_100_UM"), std::string::npos) << src.describe();
  for (int i = 0; i < 3; ++i) {
    core::Frame f;
    ASSERT_TRUE(src.next(f));
    char name[64];
    std::snprintf(name, sizeof(name), "/depth/%06d.png", i);
    // TUM units (1/5000 m) are served as 100 um units (x2), read back as x2 * 1e-4 m.
    const cv::Mat raw = cv::imread(dir + name, cv::IMREAD_UNCHANGED);
    cv::Mat expected(raw.size(), CV_32FC1);
    for (int p = 0; p < static_cast<int>(raw.total()); ++p) {
      const uint16_t v = raw.ptr<uint16_t>()[p];
      expected.ptr<float>()[p] =
          v == 0 ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>((v * 2) * 0.0001);
    }
    EXPECT_EQ(depthMismatches(f.depth, expected), 0) << i;
    EXPECT_EQ(f.timestamp_text,
              i == 0 ? "1305031102.000000" : (i == 1 ? "1305031102.100000" : "1305031102.200000"));
    EXPECT_EQ(f.color.at<cv::Vec3b>(0, 0), cv::Vec3b(static_cast<uchar>(10 * i), 100, 200));
  }
  core::Frame f;
  EXPECT_FALSE(src.next(f));
}

TEST(Openni2Virtual, ABrokenFileIsADroppedFrameReportedOnStderr) {
  // As a real sensor the device drops the frame, but it says which file and why.
  const std::string dir = makeTinyFolder(4);
  std::ofstream(dir + "/depth/000002.png", std::ios::trunc) << "not a png";
  core::SourceOptions options;
  Openni2Source src("openni2:emf-virtual://" + dir + ";speed=0", options);
  testing::internal::CaptureStderr();
  std::vector<std::string> stamps;
  core::Frame f;
  while (src.next(f)) stamps.push_back(f.timestamp_text);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(stamps, (std::vector<std::string>{"1305031102.000000", "1305031102.100000",
                                              "1305031102.300000"}));
  EXPECT_NE(err.find("emf-virtual: frame 2: depth image dropped: "), std::string::npos) << err;
  EXPECT_NE(err.find("000002.png"), std::string::npos) << err;
}

TEST(Openni2Virtual, RealTimeDeviceFramesMatchTheirPngs) {
  const std::string dir = kitchen();
  const TumList depth_list = readList(dir + "/depth.txt");
  core::SourceOptions options;
  Openni2Source src("openni2:emf-virtual://" + dir, options);  // speed 1: a 30 Hz camera
  int64_t last_index = -1;
  double last_stamp = -1;
  for (int n = 0; n < 8; ++n) {
    core::Frame f;
    ASSERT_TRUE(src.next(f));
    ASSERT_GT(f.index, last_index);  // frames may be skipped (live), never repeated
    ASSERT_GE(f.index, 0);
    ASSERT_LT(f.index, 300);
    EXPECT_GT(f.timestamp, last_stamp);
    EXPECT_NEAR(f.timestamp, depth_list.stamps[static_cast<size_t>(f.index)], 1e-6);
    EXPECT_EQ(depthMismatches(
                  f.depth,
                  expectedDepth(dir + "/" + depth_list.files[static_cast<size_t>(f.index)], 0.001)),
              0);
    last_index = f.index;
    last_stamp = f.timestamp;
  }
}

TEST(Openni2Virtual, OniRecordingPlaysBackThroughOpenNI2) {
  constexpr int kFrames = 5;
  const std::string dir = makeTinyFolder(kFrames);
  const std::string oni = test::tempDir("oni") + "/tiny.oni";
  {
    // Record the virtual camera (on-demand mode) with OpenNI2's own recorder.
    ASSERT_EQ(openni::OpenNI::initialize(), openni::STATUS_OK);
    {
      openni::Device dev;
      const std::string uri = "emf-virtual://" + dir + ";speed=0";
      ASSERT_EQ(dev.open(uri.c_str()), openni::STATUS_OK) << openni::OpenNI::getExtendedError();
      openni::VideoStream depth;
      ASSERT_EQ(depth.create(dev, openni::SENSOR_DEPTH), openni::STATUS_OK);
      openni::Recorder rec;
      ASSERT_EQ(rec.create(oni.c_str()), openni::STATUS_OK);
      ASSERT_EQ(rec.attach(depth, false), openni::STATUS_OK);
      ASSERT_EQ(depth.start(), openni::STATUS_OK);
      ASSERT_EQ(rec.start(), openni::STATUS_OK);
      // OpenNI2's recorder starts asynchronously and drops frames until its thread has seen the
      // start; no frame is produced meanwhile (on-demand device), so give it that time.
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
      for (int i = 0; i < kFrames; ++i) {
        openni::VideoStream* s[] = {&depth};
        int ready = -1;
        ASSERT_EQ(openni::OpenNI::waitForAnyStream(s, 1, &ready, 2000), openni::STATUS_OK);
        openni::VideoFrameRef f;
        ASSERT_EQ(depth.readFrame(&f), openni::STATUS_OK);
      }
      rec.stop();
      rec.destroy();
      depth.stop();
      depth.destroy();
      dev.close();
    }
    openni::OpenNI::shutdown();
  }
  ASSERT_TRUE(fs::exists(oni));
  core::SourceOptions options;
  Openni2Source src("openni2:" + oni, options);
  EXPECT_FALSE(src.isLive());
  EXPECT_NE(src.describe().find("recording"), std::string::npos) << src.describe();
  EXPECT_NEAR(src.intrinsics().fx, 50.0, kFovIntrinsicsTolerancePx);
  // Each played frame is identified by its content (pixel (row 0, column 1) = 5003 + 97 i) and must
  // equal that PNG exactly. OpenNI2's recorder renumbers frames from 1 and rebases timestamps to
  // the first recorded frame, so those are checked relative to the first frame.
  std::vector<int> seen;
  core::Frame f;
  while (src.next(f)) {
    ASSERT_LT(seen.size(), 10u) << "playback did not end";
    const int i = static_cast<int>(std::lround(f.depth.at<float>(0, 1) / 2e-4) - 5003) / 97;
    ASSERT_GE(i, 0);
    ASSERT_LT(i, kFrames);
    char name[64];
    std::snprintf(name, sizeof(name), "/depth/%06d.png", i);
    const cv::Mat raw = cv::imread(dir + name, cv::IMREAD_UNCHANGED);
    cv::Mat expected(raw.size(), CV_32FC1);
    for (int p = 0; p < static_cast<int>(raw.total()); ++p) {
      const uint16_t v = raw.ptr<uint16_t>()[p];
      expected.ptr<float>()[p] =
          v == 0 ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>((v * 2) * 0.0001);
    }
    EXPECT_EQ(depthMismatches(f.depth, expected), 0) << i;
    if (!seen.empty()) {
      EXPECT_EQ(i, seen.back() + 1) << "frames must play back in order, none skipped";
    }
    EXPECT_EQ(f.index, static_cast<int64_t>(seen.size()));
    EXPECT_NEAR(f.timestamp, 0.1 * (seen.empty() ? 0 : i - seen.front()), 1e-6);
    seen.push_back(i);
  }
  ASSERT_FALSE(seen.empty());
  EXPECT_EQ(seen.back(), kFrames - 1);  // the recording ends with the last frame read
}

template <typename Fn>
std::string errorOf(Fn&& fn) {
  try {
    fn();
  } catch (const IoError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Openni2Virtual, FullCalibrationFarDepthAndBadFolders) {
  // The principal point of calibration.txt reaches emf exactly (OpenNI2's field of view alone
  // would put it at the image centre, 32 / 24, and the focal length to float precision).
  const std::string dir = makeTinyFolder(2);
  cv::Mat far = cv::imread(dir + "/depth/000000.png", cv::IMREAD_UNCHANGED);
  far(cv::Rect(0, 0, 16, 8)).setTo(40000);  // 8 m: beyond what 100 um units hold (6.5535 m)
  ASSERT_TRUE(cv::imwrite(dir + "/depth/000000.png", far));
  core::SourceOptions options;
  {
    Openni2Source src("openni2:emf-virtual://" + dir + ";speed=0", options);
    EXPECT_EQ(src.intrinsics().fx, 50.0);
    EXPECT_EQ(src.intrinsics().fy, 52.0);
    EXPECT_EQ(src.intrinsics().cx, 31.5);
    EXPECT_EQ(src.intrinsics().cy, 23.5);
    core::Frame f;
    ASSERT_TRUE(src.next(f));
    // Invalid, not a phantom wall at 6.5535 m; the rest of the image is served as before.
    EXPECT_EQ(cv::countNonZero(f.depth(cv::Rect(0, 0, 16, 8)) == f.depth(cv::Rect(0, 0, 16, 8))),
              0);
    EXPECT_NEAR(f.depth.at<float>(20, 20), (5000 + 20 * 3 + 20) / 5000.0, 1e-4);
  }
  // A folder without calibration.txt: refused (tum: refuses it too), not served at 525 px.
  std::filesystem::remove(dir + "/calibration.txt");
  std::string e =
      errorOf([&] { Openni2Source("openni2:emf-virtual://" + dir + ";speed=0", options); });
  EXPECT_NE(e.find(dir + "/calibration.txt: missing"), std::string::npos) << e;
  // Negative timestamps would wrap around the device's unsigned microseconds.
  const std::string neg = makeTinyFolder(2);
  std::ofstream(neg + "/depth.txt") << "-1.0 depth/000000.png\n-0.9 depth/000001.png\n";
  e = errorOf([&] { Openni2Source("openni2:emf-virtual://" + neg + ";speed=0", options); });
  EXPECT_NE(e.find(neg + "/depth.txt:1: timestamp -1.000000 is negative"), std::string::npos) << e;
}

TEST(Openni2Errors, ClearMessagesForMissingDevicesAndBadParameters) {
  core::SourceOptions options;
  std::string e = errorOf([&] { Openni2Source("openni2:emf-virtual:///no/such/folder", options); });
  EXPECT_NE(e.find("cannot open device 'emf-virtual:///no/such/folder'"), std::string::npos) << e;
  EXPECT_NE(e.find("/no/such/folder/depth.txt: cannot open"), std::string::npos) << e;

  e = errorOf([&] { Openni2Source("openni2:", options); });
  EXPECT_NE(e.find("no OpenNI2 device found"), std::string::npos) << e;
  EXPECT_NE(e.find("plug in a sensor"), std::string::npos) << e;

  e = errorOf([&] { Openni2Source("openni2:/tmp/emf-none.oni", options); });
  EXPECT_NE(e.find("recording '/tmp/emf-none.oni' does not exist"), std::string::npos) << e;

  e = errorOf([&] { Openni2Source("openni2:emf-virtual://" + kitchen() + "?colour=0", options); });
  EXPECT_NE(e.find("unknown parameter 'colour'"), std::string::npos) << e;

  e = errorOf([&] { Openni2Source("openni2:emf-virtual://" + kitchen() + ";sped=2", options); });
  EXPECT_NE(e.find("unknown parameter 'sped'"), std::string::npos) << e;

  e = errorOf([&] { Openni2Source("openni2:?timeout_s=-1", options); });
  EXPECT_NE(e.find("timeout_s=-1 must be a number in"), std::string::npos) << e;
}

void writeControl(const std::string& path, const char* state) {
  std::ofstream(path) << state << "\n";
}

// Unplug / re-plug of the virtual device through its control file: the source reports the
// documented error (SensorDisconnected, state disconnected), keeps reporting it while the
// device is away, and resumes with frames that again match their PNGs.
TEST(Openni2Hotplug, UnplugIsAnErrorStateAndReplugResumes) {
  const std::string dir = kitchen();
  const TumList depth_list = readList(dir + "/depth.txt");
  std::map<std::string, size_t> index_of_stamp;
  for (size_t i = 0; i < depth_list.stamps.size(); ++i) {
    char s[32];
    std::snprintf(s, sizeof(s), "%.6f", depth_list.stamps[i]);
    index_of_stamp[s] = i;
  }
  const std::string control = test::tempDir("plug") + "/cable";
  writeControl(control, "plugged");
  core::SourceOptions options;
  auto source = openSensorSource(
      "openni2:emf-virtual://" + dir + ";control=" + control + "?timeout_s=1", options);
  auto* rs = dynamic_cast<ReconnectingSource*>(source.get());
  ASSERT_NE(rs, nullptr) << "live sensors are wrapped for hot-plug";

  auto readAndCheck = [&](int n) {
    for (int i = 0; i < n; ++i) {
      core::Frame f;
      ASSERT_TRUE(source->next(f));
      ASSERT_EQ(index_of_stamp.count(f.timestamp_text), 1u) << f.timestamp_text;
      const size_t k = index_of_stamp[f.timestamp_text];
      EXPECT_EQ(depthMismatches(f.depth, expectedDepth(dir + "/" + depth_list.files[k], 0.001)), 0);
    }
  };
  readAndCheck(3);
  EXPECT_EQ(rs->state(), SensorState::kStreaming);

  writeControl(control, "unplugged");
  int errors = 0;
  for (int attempt = 0; attempt < 3; ++attempt) {
    core::Frame f;
    try {
      // Frames already buffered before the unplug may still arrive; the error must follow.
      for (int i = 0; i < 5; ++i) source->next(f);
    } catch (const SensorDisconnected& e) {
      ++errors;
      const std::string msg = e.what();
      if (attempt == 0) {
        EXPECT_NE(msg.find("disconnected"), std::string::npos) << msg;
        EXPECT_NE(msg.find("emf-virtual://"), std::string::npos) << msg;
      } else {
        EXPECT_NE(msg.find("still disconnected"), std::string::npos) << msg;
        EXPECT_NE(msg.find("re-plug it"), std::string::npos) << msg;
      }
    }
    EXPECT_EQ(rs->state(), SensorState::kDisconnected);
  }
  EXPECT_EQ(errors, 3);
  EXPECT_EQ(rs->disconnects(), 1);

  writeControl(control, "plugged");
  readAndCheck(3);
  EXPECT_EQ(rs->state(), SensorState::kStreaming);
  EXPECT_EQ(rs->reconnects(), 1);
}

TEST(Openni2Virtual, RepeatedSensorTimestampsAreCountedNotSilentlyDropped) {
  // A sensor clock that repeats stamps (the virtual device serves depth.txt's as they are): emf
  // run tracks and fuses every frame, but a TUM file cannot hold a repeated stamp, so those poses
  // are left out of camera.txt, with a warning and run.json's count (they were dropped without a
  // word before).
  const std::string dir = test::tempDir("repeated-stamps");
  const std::string cli = EMF_CLI_PATH;
  std::string out;
  ASSERT_EQ(test::runCommand(cli + " synth room --out " + dir +
                                 "/seq --frames 6 --width 160 --height 120 --det-every 0",
                             &out),
            0)
      << out;
  fs::remove(dir + "/seq/associations.txt");
  for (const std::string list : {"depth", "rgb"}) {
    const TumList l = readList(dir + "/seq/" + list + ".txt");
    std::ofstream f(dir + "/seq/" + list + ".txt");
    for (size_t i = 0; i < l.files.size(); ++i) {
      f << std::fixed << 100.0 + 0.1 * static_cast<double>(i / 2) << " " << l.files[i] << "\n";
    }
  }
  const std::string run_dir = dir + "/run";
  ASSERT_EQ(test::runCommand(cli + " run --quiet --source 'openni2:emf-virtual://" + dir +
                                 "/seq;speed=0' --out " + run_dir,
                             &out),
            0)
      << out;
  EXPECT_NE(out.find("frame 1: timestamp 100.000000 is not after the last pose written"),
            std::string::npos)
      << out;
  std::ifstream camera(run_dir + "/camera.txt");
  std::vector<double> stamps;
  for (std::string line; std::getline(camera, line);) {
    if (!line.empty() && line[0] != '#') stamps.push_back(std::stod(line));
  }
  ASSERT_EQ(stamps.size(), 3u) << out;
  EXPECT_NEAR(stamps[2], 100.2, 1e-6);
  std::ifstream json_file(run_dir + "/run.json");
  const std::string json((std::istreambuf_iterator<char>(json_file)), {});
  EXPECT_NE(json.find("\"frames_not_in_trajectories\": 3"), std::string::npos) << json;
  EXPECT_NE(json.find("\"first_frame_not_in_trajectories\": 1"), std::string::npos) << json;
  EXPECT_NE(json.find("\"lost_frames\": 0"), std::string::npos) << json;
}

TEST(Openni2Cli, FramesTheDeviceServedWhileTheSlamWasBusyAreReportedAsDropped) {
  // The virtual device at 1000x real time serves its 20 frames far faster than the SLAM reads
  // them: OpenNI2 keeps the newest, so the frame numbers emf sees have gaps. Every frame is
  // either processed or counted as dropped (before, "5 frames (0 lost)" and nothing else).
  const std::string dir = test::tempDir("virtual-drops");
  const std::string cli = EMF_CLI_PATH;
  std::string out;
  ASSERT_EQ(test::runCommand(cli + " synth room --out " + dir +
                                 "/seq --frames 20 --width 160 --height 120 --det-every 0",
                             &out),
            0)
      << out;
  // A small map: the background mesh of the default 512^3 volume takes minutes under ASan.
  ASSERT_EQ(test::runCommand(cli + " run --quiet --source 'openni2:emf-virtual://" + dir +
                                 "/seq;speed=1000' --set map.memory_mb=32 --set "
                                 "map.background_voxel_m=0.04 --set "
                                 "map.background_resolution=128 --out " +
                                 dir + "/run",
                             &out),
            0)
      << out;
  const std::string json = test::readText(dir + "/run/run.json");
  const auto number = [&](const std::string& key) {
    const size_t at = json.find("\"" + key + "\": ");
    return at == std::string::npos ? -1 : std::stoll(json.substr(at + key.size() + 4));
  };
  const long long frames = number("frames"), dropped = number("dropped_frames");
  EXPECT_GT(dropped, 0) << json;
  EXPECT_EQ(frames + dropped, 20) << json;
  EXPECT_NE(out.find(std::to_string(dropped) + " dropped by the source"), std::string::npos) << out;
}

}  // namespace
}  // namespace emf::fw
