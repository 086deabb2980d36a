// Detector scheduling, async mode (label threads: also run under ThreadSanitizer): frames are
// copied into the slot, dropped while the detector is busy, and late results carry the frame
// and poses they were computed on. A gate held by the test makes the detector "busy" without
// any timing assumption.
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <condition_variable>
#include <mutex>

#include "pipeline/detector_scheduler.h"
#include "test_support.h"

namespace emf::pipeline {
namespace {

constexpr double kPoseTolerance = 1e-12;  // poses are copied, not computed

core::Intrinsics smallCamera() { return test::camera80x60(); }

core::Frame makeFrame(int64_t index) {
  core::Frame f;
  f.index = index;
  f.timestamp = 5.0 + 0.5 * static_cast<double>(index);
  f.timestamp_text = std::to_string(f.timestamp);
  f.depth = cv::Mat(60, 80, CV_32F, cv::Scalar(1.0f + 0.01f * static_cast<float>(index)));
  f.color = cv::Mat(60, 80, CV_8UC3, cv::Scalar(1, 2, 3));
  return f;
}

Eigen::Isometry3d poseOf(int64_t index) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.1 * static_cast<double>(index), 0.0, 1.0);
  return T;
}

// Blocks every detect() call until the test opens it; counts the calls.
class Gate {
 public:
  void open() {
    std::lock_guard<std::mutex> lock(m_);
    open_ = true;
    cv_.notify_all();
  }
  void close() {
    std::lock_guard<std::mutex> lock(m_);
    open_ = false;
  }
  void pass() {
    std::unique_lock<std::mutex> lock(m_);
    ++entered_;
    cv_.notify_all();
    cv_.wait(lock, [this] { return open_; });
    ++calls_;
  }
  // Waits until `n` calls have reached the gate.
  void waitEntered(int n) {
    std::unique_lock<std::mutex> lock(m_);
    cv_.wait(lock, [this, n] { return entered_ >= n; });
  }
  int calls() {
    std::lock_guard<std::mutex> lock(m_);
    return calls_;
  }

 private:
  std::mutex m_;
  std::condition_variable cv_;
  bool open_ = false;
  int entered_ = 0;
  int calls_ = 0;
};

// Reports one detection whose score is the depth it saw minus 1 (= 0.01 * frame index).
DetectorScheduler::DetectFunction gated(Gate* gate) {
  return [gate](const core::Frame& f, const cv::Mat*, const cv::Mat* residual) {
    gate->pass();
    DetectorOutput out;
    core::Detection d;
    d.id = 1;
    d.class_name = "toy_car";
    d.score = f.depth.at<float>(3, 3) - 1.0f;
    d.box = cv::Rect(0, 0, 8, 8);
    d.mask =
        cv::Mat(f.depth.size(), CV_32F, cv::Scalar(residual ? residual->at<float>(0, 0) : 1.0f));
    out.detections.push_back(d);
    return out;
  };
}

DetectorOptions async(int every_n) {
  DetectorOptions o;
  o.mode = DetectorMode::kAsync;
  o.every_n_frames = every_n;
  return o;
}

TEST(DetectorSchedulerAsync, BusyDetectorDropsFramesAndLateResultCarriesItsFrame) {
  Gate gate;
  DetectorScheduler s(async(1), "gated", gated(&gate), smallCamera());
  ASSERT_TRUE(s.async());
  core::Frame f0 = makeFrame(0);
  const cv::Mat residual0(60, 80, CV_32F, cv::Scalar(0.75f));
  const std::vector<ObjectPose> objects0 = {{2, poseOf(20)}};
  EXPECT_FALSE(s.submit(f0, poseOf(0), nullptr, &residual0, &objects0).has_value());
  // The caller's buffers are free right after submit(): the detector works on its copy.
  f0.depth.setTo(9.0f);
  for (int64_t i = 1; i <= 4; ++i) {
    EXPECT_FALSE(s.submit(makeFrame(i), poseOf(i)).has_value());  // busy: dropped
  }
  EXPECT_EQ(s.stats().dropped_frames, 4);
  gate.open();
  s.waitIdle();
  // The result of frame 0 arrives with frame 5: five frames late.
  const auto b = s.submit(makeFrame(5), poseOf(5));
  ASSERT_TRUE(b.has_value());
  EXPECT_EQ(b->frame_index, 0);
  EXPECT_EQ(b->frames_late, 5);
  EXPECT_DOUBLE_EQ(b->timestamp, 5.0);
  EXPECT_TRUE(b->T_world_camera.isApprox(poseOf(0), kPoseTolerance));
  ASSERT_EQ(b->objects.size(), 1u);
  EXPECT_EQ(b->objects[0].id, 2);
  EXPECT_TRUE(b->objects[0].T_world_object.isApprox(poseOf(20), kPoseTolerance));
  ASSERT_EQ(b->detections.size(), 1u);
  EXPECT_NEAR(b->detections[0].score, 0.0, 1e-6);  // depth of frame 0, not the overwritten 9
  EXPECT_FLOAT_EQ(b->detections[0].mask.at<float>(1, 1), 0.75f);  // residual copied too
  // Frame 5 was handed over by that submit(); finish() collects it.
  const auto last = s.finish();
  ASSERT_TRUE(last.has_value());
  EXPECT_EQ(last->frame_index, 5);
  EXPECT_NEAR(last->detections.at(0).score, 0.05, 1e-6);
  EXPECT_FLOAT_EQ(last->detections.at(0).mask.at<float>(1, 1), 1.0f);  // no residual given
  EXPECT_FALSE(s.finish().has_value());
  const DetectorStats st = s.stats();
  EXPECT_EQ(gate.calls(), 2);
  EXPECT_EQ(st.runs, 2);
  EXPECT_EQ(st.dropped_frames, 4);
  EXPECT_EQ(st.results_delivered, 2);
  EXPECT_EQ(st.mode, "async");
}

TEST(DetectorSchedulerAsync, OnlyDueFramesAreHandedOver) {
  Gate gate;
  gate.open();
  DetectorScheduler s(async(3), "gated", gated(&gate), smallCamera());
  EXPECT_FALSE(s.submit(makeFrame(0), poseOf(0)).has_value());
  s.waitIdle();
  // Frames 1 and 2 are not due: not handed over, not dropped; frame 0's result comes back.
  const auto r1 = s.submit(makeFrame(1), poseOf(1));
  ASSERT_TRUE(r1.has_value());
  EXPECT_EQ(r1->frame_index, 0);
  EXPECT_FALSE(s.submit(makeFrame(2), poseOf(2)).has_value());
  EXPECT_FALSE(s.submit(makeFrame(3), poseOf(3)).has_value());  // handed over
  s.waitIdle();
  gate.close();
  // submit(6) first takes frame 3's result, then hands frame 6 over (the slot holds one frame,
  // so a result is always collected before the next hand-over).
  const auto r6 = s.submit(makeFrame(6), poseOf(6));
  ASSERT_TRUE(r6.has_value());
  EXPECT_EQ(r6->frame_index, 3);
  EXPECT_EQ(r6->frames_late, 3);
  gate.open();
  s.waitIdle();
  const auto r7 = s.submit(makeFrame(7), poseOf(7));
  ASSERT_TRUE(r7.has_value());
  EXPECT_EQ(r7->frame_index, 6);
  EXPECT_EQ(r7->frames_late, 1);
  const DetectorStats st = s.stats();
  EXPECT_EQ(gate.calls(), 3);  // frames 0, 3, 6
  EXPECT_EQ(st.runs, 3);
  EXPECT_EQ(st.dropped_frames, 0);
  EXPECT_EQ(st.results_delivered, 3);
}

TEST(DetectorSchedulerAsync, DestroyWhileDetecting) {
  Gate gate;
  auto s = std::make_unique<DetectorScheduler>(async(1), "gated", gated(&gate), smallCamera());
  EXPECT_FALSE(s->submit(makeFrame(0), poseOf(0)).has_value());
  gate.waitEntered(1);  // the detector thread is inside detect()
  gate.open();          // the destructor waits for the running call, then stops the thread
  s.reset();
  EXPECT_EQ(gate.calls(), 1);
}

TEST(DetectorSchedulerAsync, PluginOnTheDetectorThread) {
  DetectorOptions o = async(1);
  o.plugin = "test_malformed";
  o.search_path = {EMF_TEST_PLUGIN_DIR};
  DetectorScheduler s(o, "", smallCamera());
  for (int64_t i = 0; i < 3; ++i) {
    s.submit(makeFrame(i), poseOf(i));
    s.waitIdle();
  }
  const auto b = s.finish();
  ASSERT_TRUE(b.has_value());
  EXPECT_EQ(b->frame_index, 2);
  ASSERT_EQ(b->detections.size(), 1u);
  EXPECT_EQ(b->detections[0].class_name, "cup");
  const DetectorStats st = s.stats();
  EXPECT_EQ(st.runs, 3);
  EXPECT_EQ(st.rejected, 15);
  EXPECT_EQ(st.dropped_frames, 0);
}

}  // namespace
}  // namespace emf::pipeline

namespace emf::pipeline {
namespace {

int threadNice() {
  errno = 0;
  return ::getpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)));
}

// detector.nice: the detector thread runs at that niceness, the submitting (SLAM) thread keeps
// its own. 19 can always be set without privileges.
TEST(DetectorSchedulerAsync, TheDetectorThreadRunsAtDetectorNice) {
  const int slam_nice = threadNice();
  std::atomic<int> detector_nice{-100};
  DetectorOptions o = async(1);
  o.nice = 19;
  DetectorScheduler s(
      o, "nice",
      [&](const core::Frame&, const cv::Mat*, const cv::Mat*) {
        detector_nice = threadNice();
        return DetectorOutput{};
      },
      smallCamera());
  s.submit(makeFrame(0), poseOf(0));
  s.waitIdle();
  EXPECT_EQ(detector_nice.load(), 19);
  EXPECT_EQ(threadNice(), slam_nice);
}

}  // namespace
}  // namespace emf::pipeline
