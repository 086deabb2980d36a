// The dnn plugin through the real path a user takes: `emf run --detector dnn` on a synthetic
// sequence, the plugin found by name on the build's plugin folder and loaded with dlopen by the
// detector scheduler. The generated model returns a fixed "person" and a fixed "cup" instance on
// every call; run.json must count exactly those, the person must not create an object (objects.
// track_person is off) and the cup must.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "dnn_test_truth.h"
#include "test_support.h"

namespace {

using emf_dnn_test::modelPath;

constexpr int kFrames = 4;
constexpr int kEveryN = 2;
constexpr int kInstancesPerCall = 2;  // person + cup (yolov8_seg.json)

TEST(DnnRun, EmfRunWithTheDnnDetectorOnASyntheticSequence) {
  const std::string out = emf::test::tempDir("dnn_run");
  const std::string cmd =
      std::string(EMF_CLI_PATH) +
      " run --quiet --source 'synth:room?frames=" + std::to_string(kFrames) +
      "&width=320&height=240' --detector dnn --detector-config 'model=" +
      modelPath("yolov8_seg.onnx") +
      ",layout=yolov8' --set detector.every_n_frames=" + std::to_string(kEveryN) +
      " --set map.background_voxel_m=0.02 --set map.background_resolution=256"
      " --out " +
      out;
  std::string output;
  ASSERT_EQ(emf::test::runCommand(cmd + " 2>&1", &output), 0) << output;
  std::ifstream in(out + "/run.json");
  ASSERT_TRUE(in) << output;
  const nlohmann::json j = nlohmann::json::parse(in);
  const nlohmann::json& d = j.at("detector");
  EXPECT_EQ(d.at("plugin"), "dnn");
  EXPECT_EQ(d.at("runs"), kFrames / kEveryN);
  EXPECT_EQ(d.at("failures"), 0);
  EXPECT_EQ(d.at("rejected_detections"), 0);
  EXPECT_EQ(d.at("detections"), kFrames / kEveryN * kInstancesPerCall);
  int cups = 0;
  for (const auto& o : j.at("objects")) {
    EXPECT_NE(o.at("class"), "person");
    if (o.at("class") == "cup") ++cups;
  }
  EXPECT_EQ(cups, 1) << j.at("objects").dump();
}

}  // namespace
