// Confirmation (objects.confirm_detections) in the running SLAM: a still box detected every 30
// frames and one false detection, a blob on the back wall on frame 30. With confirmation (2) the
// box is reported from its second detection with its poses since creation, and the blob, never
// detected again, is dropped without ever being reported; reported at once (1, the paper), the
// blob is an object.
#include <gtest/gtest.h>

#include <map>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "box_room_scene.h"
#include "pipeline/slam_system.h"
#include "synth/synth_source.h"
#include "test_support.h"

namespace emf::pipeline {
namespace {

constexpr int kWidth = 320, kHeight = 240;
constexpr int kFrames = 120;
constexpr int kBoxId = 1;

synth::Scene stillBoxScene() {
  synth::Scene s = test_scene::boxRoomScene("still-box", kBoxId, -0.2, 0.6);
  s.camera.path.origin_m = Eigen::Vector3d(0, -1.6, 1.2);
  s.camera.path.position_terms = {{Eigen::Vector3d(0.15, 0, 0), 0.2, 0.0}};
  s.camera.target.origin_m = Eigen::Vector3d(0, 0.6, 0.3);
  s.default_frames = kFrames;
  return s;
}

/// A false detection: an ellipse on the wall above the box.
core::Detection blob() {
  core::Detection d;
  d.id = 2;
  d.class_name = "cup";
  d.score = 0.6f;
  cv::Mat mask = cv::Mat::zeros(kHeight, kWidth, CV_8U);
  cv::ellipse(mask, cv::Point(230, 40), cv::Size(22, 16), 0, 0, 360, cv::Scalar(255), cv::FILLED);
  mask.convertTo(d.mask, CV_32F, 1.0 / 255);
  d.box = cv::boundingRect(mask);
  return d;
}

struct Reported {
  std::map<int, int> tracked_frames;  // per reported id: frames in outcomes and backlogs
  std::map<int, int> first_reported;  // per reported id: frame it first appeared in
  int box_id = -1;
};

Reported run(int confirm_detections) {
  Config config = test_scene::smallSceneConfig();
  config.objects.confirm_detections = confirm_detections;
  cl::Context ctx(config.cl);
  synth::SynthOptions so;
  so.width = kWidth;
  so.height = kHeight;
  synth::SynthSource src(so, stillBoxScene());
  SlamSystem slam(ctx, config, src.intrinsics());
  Reported r;
  core::Frame f;
  while (src.next(f)) {
    std::vector<core::Detection> dets;
    const bool detect = f.index % 30 == 0;
    if (detect) dets.push_back(test_scene::exactDetection(f, kBoxId));
    if (f.index == 30) dets.push_back(blob());
    const FrameOutcome out = slam.process(f, detect ? &dets : nullptr);
    for (const ConfirmedObject& c : out.confirmed) {
      r.tracked_frames[c.id] += static_cast<int>(c.earlier.size());
    }
    for (const ObjectOutcome& o : out.objects) {
      r.first_reported.emplace(o.id, static_cast<int>(f.index));
      if (o.state == ObjectState::kTracked) ++r.tracked_frames[o.id];
      if (o.first_frame == 0) r.box_id = o.id;
    }
  }
  return r;
}

TEST(SlamConfirm, AFalseDetectionIsNeverReportedAndTheBoxKeepsItsFirstFrames) {
  const Reported confirmed = run(2);
  const Reported at_once = run(1);
  // With confirmation: the box only, first reported with its second detection, its trajectory
  // complete; the blob never.
  ASSERT_GE(confirmed.box_id, 0);
  EXPECT_EQ(confirmed.first_reported.size(), 1u) << "the blob was reported";
  EXPECT_EQ(confirmed.first_reported.at(confirmed.box_id), 30);
  EXPECT_EQ(confirmed.tracked_frames.at(confirmed.box_id), kFrames);
  // At once: the box from frame 0 and the blob from frame 30.
  ASSERT_GE(at_once.box_id, 0);
  EXPECT_EQ(at_once.first_reported.at(at_once.box_id), 0);
  EXPECT_EQ(at_once.tracked_frames.at(at_once.box_id), kFrames);
  EXPECT_EQ(at_once.first_reported.size(), 2u) << "the blob must make an object at once";
}

}  // namespace
}  // namespace emf::pipeline
