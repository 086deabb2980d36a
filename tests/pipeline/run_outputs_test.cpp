// run.json with the optional parts: the objects array, the detector counters and the error of an
// interrupted run, through runSummaryJson / writeFinalOutputs on a real (empty) SlamSystem.
#include "pipeline/run_outputs.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "test_support.h"

namespace emf::pipeline {
namespace {

Config tinyConfig() {
  Config c;
  c.map.memory_mb = 16;
  c.map.background_voxel_m = 0.04;
  c.map.background_resolution = 64;
  return c;
}

core::Intrinsics tinyCamera() {
  core::Intrinsics k;
  k.fx = k.fy = 65.625;
  k.cx = 39.5;
  k.cy = 29.5;
  k.width = 80;
  k.height = 60;
  return k;
}

class RunOutputs : public test::WithClContext {};

TEST_F(RunOutputs, SummaryHasObjectsDetectorAndError) {
  SlamSystem slam(ctx(), tinyConfig(), tinyCamera());
  RunInfo info;
  info.source_uri = "synth:cars";
  ObjectSummary car;
  car.id = 3;
  car.class_name = "car";
  car.first_frame = 10;
  car.last_frame = 20;
  car.frames_tracked = 11;
  car.deleted = true;
  car.deleted_frame = 21;
  car.deleted_reason = "invisible for 30 frames";
  info.objects = std::vector<ObjectSummary>{car};
  DetectorStats st;
  st.plugin = "maskfile";
  st.runs = 2;
  st.dropped_frames = 5;
  st.labelled_frames_skipped = 29;
  info.detector = st;
  info.error = "stopped after 22 frames: broken";
  info.run_id = "20261127T000000Z-42";
  info.status = RunStatus::kFailed;
  const std::string dir = test::tempDir("run-outputs");
  writeFinalOutputs(dir, slam, ctx(), info, true);
  const nlohmann::json j = nlohmann::json::parse(test::readText(dir + "/run.json"));
  EXPECT_EQ(j["run_id"], "20261127T000000Z-42");
  EXPECT_EQ(j["status"], "failed");
  ASSERT_EQ(j["objects"].size(), 1u);
  EXPECT_EQ(j["objects"][0]["id"], 3);
  EXPECT_EQ(j["objects"][0]["class"], "car");
  EXPECT_EQ(j["objects"][0]["state"], "deleted");
  EXPECT_EQ(j["objects"][0]["deleted_reason"], "invisible for 30 frames");
  EXPECT_EQ(j["objects"][0]["last_frame"], 20);
  EXPECT_EQ(j["detector"]["plugin"], "maskfile");
  EXPECT_EQ(j["detector"]["runs"], 2);
  EXPECT_EQ(j["detector"]["dropped_frames"], 5);
  EXPECT_EQ(j["detector"]["labelled_frames_skipped"], 29);
  EXPECT_EQ(j["error"], "stopped after 22 frames: broken");
  EXPECT_TRUE(std::filesystem::exists(dir + "/background.ply"));
  // Without them, the keys are absent (a run without objects support reads as before).
  const nlohmann::json plain = nlohmann::json::parse(runSummaryJson(slam, ctx(), RunInfo()));
  EXPECT_FALSE(plain.contains("objects"));
  EXPECT_FALSE(plain.contains("detector"));
  EXPECT_FALSE(plain.contains("error"));
  EXPECT_EQ(plain["status"], "running");
  EXPECT_FALSE(plain.contains("signal"));
  // The work counters are always there (no frames yet: count 0).
  for (const char* counter : {"track_iterations", "object_track_iterations", "object_track_pixels",
                              "integrated_blocks", "kernel_launches", "host_waits", "bytes_read"}) {
    ASSERT_TRUE(plain["work_per_frame"].contains(counter)) << counter;
    EXPECT_EQ(plain["work_per_frame"][counter]["count"], 0) << counter;
  }
}

}  // namespace
}  // namespace emf::pipeline
