// Detector scheduling, sequential mode: which frames run the detector, what a batch carries
// (frame, poses), counters, once-per-kind problems, and the plugin lookup errors.
#include "pipeline/detector_scheduler.h"

#include "common/error.h"
#include "test_support.h"

namespace emf::pipeline {
namespace {

constexpr double kPoseTolerance = 1e-12;  // poses are copied, not computed

core::Intrinsics smallCamera() { return test::camera80x60(); }

core::Frame makeFrame(int64_t index) {
  core::Frame f;
  f.index = index;
  f.timestamp = 100.0 + 0.1 * static_cast<double>(index);
  f.timestamp_text = std::to_string(f.timestamp);
  f.depth = cv::Mat(60, 80, CV_32F, cv::Scalar(1.0f + 0.01f * static_cast<float>(index)));
  f.color = cv::Mat(60, 80, CV_8UC3, cv::Scalar(10, 20, 30));
  return f;
}

Eigen::Isometry3d poseOf(int64_t index) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.01 * static_cast<double>(index), -0.5, 2.0);
  T.linear() = Eigen::AngleAxisd(0.02 * static_cast<double>(index), Eigen::Vector3d::UnitY())
                   .toRotationMatrix();
  return T;
}

// A detection covering the whole 80x60 image, as a source's stored detections.
core::Detection wholeImageCar() {
  core::Detection d;
  d.class_name = "car";
  d.score = 1.f;
  d.box = cv::Rect(0, 0, 4, 4);
  d.mask = cv::Mat(60, 80, CV_32F, cv::Scalar(1.f));
  return d;
}

DetectorOptions sequential(int every_n) {
  DetectorOptions o;
  o.mode = DetectorMode::kSequential;
  o.every_n_frames = every_n;
  return o;
}

// A detector that reports one box whose score encodes the depth it saw (1 + 0.01 index).
DetectorScheduler::DetectFunction depthEcho(std::vector<int64_t>* calls) {
  return [calls](const core::Frame& f, const cv::Mat* q0, const cv::Mat* residual) {
    calls->push_back(f.index);
    DetectorOutput out;
    core::Detection d;
    d.id = 1;
    d.class_name = q0 ? "with_q0" : "car";
    d.score = f.depth.at<float>(0, 0) - 1.0f;
    d.box = cv::Rect(1, 2, 3, 4);
    d.mask = cv::Mat(f.depth.size(), CV_32F, cv::Scalar(residual ? 0.5f : 1.0f));
    out.detections.push_back(d);
    return out;
  };
}

TEST(DetectorScheduler, SequentialRunsOnEveryNthFrameWithThatFramesPoses) {
  std::vector<int64_t> calls;
  DetectorScheduler s(sequential(3), "echo", depthEcho(&calls), smallCamera());
  ASSERT_TRUE(s.enabled());
  EXPECT_FALSE(s.async());
  std::vector<int64_t> batches;
  for (int64_t i = 0; i < 10; ++i) {
    const std::vector<ObjectPose> objects = {{4, poseOf(i + 7)}, {9, poseOf(i + 8)}};
    const auto b = s.submit(makeFrame(i), poseOf(i), nullptr, nullptr, &objects);
    if (!b) continue;
    batches.push_back(b->frame_index);
    EXPECT_EQ(b->frame_index, i);
    EXPECT_DOUBLE_EQ(b->timestamp, 100.0 + 0.1 * static_cast<double>(i));
    EXPECT_EQ(b->frames_late, 0);
    EXPECT_TRUE(b->T_world_camera.isApprox(poseOf(i), kPoseTolerance));
    ASSERT_EQ(b->objects.size(), 2u);
    EXPECT_EQ(b->objects[1].id, 9);
    EXPECT_TRUE(b->objects[1].T_world_object.isApprox(poseOf(i + 8), kPoseTolerance));
    ASSERT_EQ(b->detections.size(), 1u);
    EXPECT_NEAR(b->detections[0].score, 0.01 * static_cast<double>(i), 1e-6);
    EXPECT_EQ(b->detections[0].class_name, "car");
    EXPECT_FALSE(b->new_objects_only);
  }
  EXPECT_EQ(batches, (std::vector<int64_t>{0, 3, 6, 9}));
  EXPECT_EQ(calls, batches);
  const DetectorStats st = s.stats();
  EXPECT_EQ(st.plugin, "echo");
  EXPECT_EQ(st.mode, "sequential");
  EXPECT_EQ(st.runs, 4);
  EXPECT_EQ(st.detections, 4);
  EXPECT_EQ(st.failures, 0);
  EXPECT_EQ(st.dropped_frames, 0);
  EXPECT_EQ(st.results_delivered, 4);
  EXPECT_GE(st.detector_ms_max, st.detector_ms_median);
  EXPECT_FALSE(s.finish().has_value());  // nothing pending in sequential mode
}

TEST(DetectorScheduler, BatchCarriesTheNewObjectsOnlyFlag) {
  DetectorScheduler s(
      sequential(1), "motion-like",
      [](const core::Frame&, const cv::Mat*, const cv::Mat*) {
        DetectorOutput out;
        out.new_objects_only = true;
        return out;
      },
      smallCamera());
  const auto b = s.submit(makeFrame(0), poseOf(0));
  ASSERT_TRUE(b.has_value());
  EXPECT_TRUE(b->new_objects_only);
}

TEST(DetectorScheduler, FeedbackImagesReachTheDetector) {
  std::vector<int64_t> calls;
  DetectorScheduler s(sequential(1), "echo", depthEcho(&calls), smallCamera());
  const cv::Mat q0(60, 80, CV_32F, cv::Scalar(0.25f)), residual(60, 80, CV_32F, cv::Scalar(0.f));
  const auto b = s.submit(makeFrame(0), poseOf(0), &q0, &residual);
  ASSERT_TRUE(b && b->detections.size() == 1u);
  EXPECT_EQ(b->detections[0].class_name, "with_q0");
  EXPECT_FLOAT_EQ(b->detections[0].mask.at<float>(5, 5), 0.5f);
}

TEST(DetectorScheduler, ThrowingDetectorIsAFailureNotACrash) {
  DetectorScheduler s(
      sequential(1), "thrower",
      [](const core::Frame&, const cv::Mat*, const cv::Mat*) -> DetectorOutput {
        throw std::runtime_error("out of memory in layer 3");
      },
      smallCamera());
  for (int64_t i = 0; i < 3; ++i) {
    const auto b = s.submit(makeFrame(i), poseOf(i), nullptr, nullptr);
    ASSERT_TRUE(b.has_value());
    EXPECT_TRUE(b->detections.empty());
  }
  const DetectorStats st = s.stats();
  EXPECT_EQ(st.runs, 3);
  EXPECT_EQ(st.failures, 3);
  ASSERT_EQ(st.problems.size(), 1u);  // frames 0, 1, 2: one kind
  EXPECT_EQ(st.problems.begin()->second, 3);
  EXPECT_NE(st.problems.begin()->first.find("detect threw: out of memory in layer #"),
            std::string::npos)
      << st.problems.begin()->first;
}

TEST(DetectorScheduler, ProblemKindReplacesNumbers) {
  EXPECT_EQ(problemKind("detector 'x' frame 12 detection 3: score 1.5 is not in [0, 1]"),
            "detector 'x' frame # detection #: score #.# is not in [#, #]");
  EXPECT_EQ(problemKind("no digits"), "no digits");
}

TEST(DetectorScheduler, NoPluginIsDisabledAndIgnoresSourceDetections) {
  DetectorScheduler s(sequential(1), "", smallCamera());
  EXPECT_FALSE(s.enabled());
  core::Frame f = makeFrame(0);
  const core::Detection d = wholeImageCar();
  f.detections = std::vector<core::Detection>{d};
  EXPECT_FALSE(s.submit(f, poseOf(0)).has_value());
  EXPECT_EQ(s.stats().runs, 0);
  EXPECT_EQ(s.stats().plugin, "");
}

TEST(DetectorScheduler, LabelledFramesOffTheScheduleAreCountedAndWarnedOnce) {
  // A dataset with detections on every frame, replayed every 3rd frame: frames 1, 2, 4, 5, 7
  // and 8 carry labels the detector never sees. Frames without labels (6: none, 9: an empty
  // list) are not counted.
  std::vector<int64_t> calls;
  DetectorScheduler s(sequential(3), "echo", depthEcho(&calls), smallCamera());
  const core::Detection d = wholeImageCar();
  testing::internal::CaptureStderr();
  for (int64_t i = 0; i < 10; ++i) {
    core::Frame f = makeFrame(i);
    if (i == 9) {
      f.detections = std::vector<core::Detection>{};
    } else if (i != 6) {
      f.detections = std::vector<core::Detection>{d};
    }
    s.submit(f, poseOf(i));
  }
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(s.stats().labelled_frames_skipped, 6);
  EXPECT_EQ(s.stats().runs, 4);
  EXPECT_EQ(calls, (std::vector<int64_t>{0, 3, 6, 9}));
  const size_t first = err.find("detector.every_n_frames=1");
  ASSERT_NE(first, std::string::npos) << err;
  EXPECT_EQ(err.find("detector.every_n_frames=1", first + 1), std::string::npos)
      << "warned more than once: " << err;
  EXPECT_NE(err.find("frame 1 carries detections"), std::string::npos) << err;
}

TEST(DetectorScheduler, LabelledFramesOnTheScheduleAreNotCounted) {
  std::vector<int64_t> calls;
  DetectorScheduler s(sequential(1), "echo", depthEcho(&calls), smallCamera());
  const core::Detection d = wholeImageCar();
  testing::internal::CaptureStderr();
  for (int64_t i = 0; i < 5; ++i) {
    core::Frame f = makeFrame(i);
    f.detections = std::vector<core::Detection>{d};
    s.submit(f, poseOf(i));
  }
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(s.stats().labelled_frames_skipped, 0);
  EXPECT_EQ(s.stats().runs, 5);
  EXPECT_EQ(err.find("every_n_frames"), std::string::npos) << err;
}

// ---- through the plugin host ---------------------------------------------------------------

DetectorOptions withPlugin(const std::string& name, DetectorMode mode = DetectorMode::kSequential) {
  DetectorOptions o;
  o.plugin = name;
  o.search_path = {EMF_TEST_PLUGIN_DIR};
  o.mode = mode;
  o.every_n_frames = 2;
  return o;
}

TEST(DetectorScheduler, MalformedPluginResultsAreCountedOncePerKind) {
  DetectorScheduler s(withPlugin("test_malformed"), "", smallCamera());
  EXPECT_EQ(s.name(), "test");
  int with_detection = 0;
  for (int64_t i = 0; i < 6; ++i) {
    const auto b = s.submit(makeFrame(i), poseOf(i));
    if (!b) continue;
    ASSERT_EQ(b->detections.size(), 1u);  // the good one of six
    EXPECT_EQ(b->detections[0].class_name, "cup");
    EXPECT_DOUBLE_EQ(cv::sum(b->detections[0].mask)[0], 40.0 * 20.0);
    ++with_detection;
  }
  EXPECT_EQ(with_detection, 3);  // frames 0, 2, 4
  const DetectorStats st = s.stats();
  EXPECT_EQ(st.runs, 3);
  EXPECT_EQ(st.failures, 0);
  EXPECT_EQ(st.detections, 3);
  EXPECT_EQ(st.rejected, 15);
  // Five kinds of malformed detection (NaN score, box, mask size, probabilities, empty class),
  // each seen on all three runs.
  ASSERT_EQ(st.problems.size(), 5u);
  for (const auto& [kind, count] : st.problems) EXPECT_EQ(count, 3) << kind;
}

TEST(DetectorScheduler, FailingPluginKeepsGoing) {
  DetectorScheduler s(withPlugin("test_failing"), "", smallCamera());
  for (int64_t i = 0; i < 4; ++i) {
    const auto b = s.submit(makeFrame(i), poseOf(i));
    EXPECT_EQ(b.has_value(), i % 2 == 0);
    if (b) {
      EXPECT_TRUE(b->detections.empty());
    }
  }
  const DetectorStats st = s.stats();
  EXPECT_EQ(st.runs, 2);
  EXPECT_EQ(st.failures, 2);
  ASSERT_EQ(st.problems.size(), 1u);
  EXPECT_NE(st.problems.begin()->first.find("detect always fails"), std::string::npos);
}

TEST(DetectorScheduler, UnknownPluginListsTheFoldersSearched) {
  DetectorOptions o = withPlugin("nosuch");
  o.search_path = {"/tmp/emf-folder-a", "/tmp/emf-folder-b"};
  try {
    DetectorScheduler s(o, "", smallCamera());
    FAIL() << "no error for a missing plugin";
  } catch (const PluginError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("'nosuch' not found"), std::string::npos) << m;
    EXPECT_NE(m.find("/tmp/emf-folder-a"), std::string::npos) << m;
    EXPECT_NE(m.find("/tmp/emf-folder-b"), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace emf::pipeline
