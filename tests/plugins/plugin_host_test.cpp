// The detector plugin host: lookup, ABI checks, result validation, and the maskfile plugin.
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "pipeline/detector_plugin.h"
#include "test_support.h"

namespace emf::pipeline {
namespace {

const std::vector<std::string> kTestPath = {EMF_TEST_PLUGIN_DIR};
const std::vector<std::string> kBuildPath = {EMF_PLUGIN_BUILD_DIR};

core::Intrinsics smallCamera() { return test::camera80x60(); }

core::Frame frame(int64_t index, const std::string& stamp) {
  core::Frame f;
  f.index = index;
  f.timestamp_text = stamp;
  f.timestamp = std::stod(stamp);
  f.depth = cv::Mat(60, 80, CV_32F, cv::Scalar(1.5f));
  f.color = cv::Mat(60, 80, CV_8UC3, cv::Scalar(10, 20, 30));
  return f;
}

std::string loadError(const std::string& name, const std::vector<std::string>& path,
                      const std::string& config = "") {
  try {
    DetectorPlugin::load(name, path, config, "", smallCamera());
  } catch (const PluginError& e) {
    return e.what();
  }
  return "";
}

TEST(PluginHost, NotFoundListsSearchedFolders) {
  const std::string e = loadError("nosuch", {"/tmp/a", "/tmp/b"});
  EXPECT_NE(e.find("'nosuch' not found"), std::string::npos) << e;
  EXPECT_NE(e.find("/tmp/a"), std::string::npos) << e;
  EXPECT_NE(e.find("/tmp/b"), std::string::npos) << e;
  const std::string e2 = loadError("/nonexistent/libx.so", {});
  EXPECT_NE(e2.find("/nonexistent/libx.so' does not exist"), std::string::npos) << e2;
}

TEST(PluginHost, NotAPluginFileIsAClearError) {
  const std::string dir = test::tempDir("notaplugin");
  { std::ofstream(dir + "/libemf_detector_junk.so") << "not an ELF file"; }
  const std::string e = loadError("junk", {dir});
  EXPECT_NE(e.find("cannot load detector plugin"), std::string::npos) << e;
}

TEST(PluginHost, MissingEntrySymbol) {
  const std::string e = loadError("test_noentry", kTestPath);
  EXPECT_NE(e.find("does not export emf_detector_entry"), std::string::npos) << e;
}

TEST(PluginHost, AbiVersionMismatch) {
  const std::string e = loadError("test_badabi", kTestPath);
  EXPECT_NE(e.find("ABI version 999"), std::string::npos) << e;
  const std::string e2 = loadError("test_refuses", kTestPath);
  EXPECT_NE(e2.find("refused host ABI version 1"), std::string::npos) << e2;
}

TEST(PluginHost, CreateFailureCarriesPluginMessage) {
  const std::string e = loadError("test_failing", kTestPath, "fail");
  EXPECT_NE(e.find("test plugin: asked to fail"), std::string::npos) << e;
}

TEST(PluginHost, FailedDetectYieldsNoDetectionsAndAMessage) {
  auto p = DetectorPlugin::load("test_failing", kTestPath, "", "", smallCamera());
  const DetectorOutput out = p->detect(frame(3, "0.100000"));
  EXPECT_TRUE(out.detections.empty());
  EXPECT_NE(out.error.find("frame 3"), std::string::npos) << out.error;
  EXPECT_NE(out.error.find("detect always fails"), std::string::npos) << out.error;
}

TEST(PluginHost, MalformedDetectionsAreDroppedGoodOneKept) {
  auto p = DetectorPlugin::load("test_malformed", kTestPath, "", "", smallCamera());
  for (int round = 0; round < 3; ++round) {  // repeated calls: no state corruption
    const DetectorOutput out = p->detect(frame(round, "1.000000"));
    EXPECT_TRUE(out.error.empty()) << out.error;
    ASSERT_EQ(out.detections.size(), 1u);
    const core::Detection& d = out.detections[0];
    EXPECT_EQ(d.id, 1);
    EXPECT_EQ(d.class_name, "cup");
    EXPECT_FLOAT_EQ(d.score, 0.9f);
    EXPECT_EQ(d.box, cv::Rect(20, 10, 40, 20));
    EXPECT_DOUBLE_EQ(cv::sum(d.mask)[0], 40.0 * 20.0);
    EXPECT_FLOAT_EQ(d.mask.at<float>(10, 20), 1.f);
    EXPECT_FLOAT_EQ(d.mask.at<float>(9, 20), 0.f);
    ASSERT_EQ(out.rejected.size(), 5u);
    EXPECT_NE(out.rejected[0].find("score nan is not in [0, 1]"), std::string::npos)
        << out.rejected[0];
    EXPECT_NE(out.rejected[1].find("is not inside the 80x60 image"), std::string::npos)
        << out.rejected[1];
    EXPECT_NE(out.rejected[2].find("mask is 2x2, the depth image is 80x60"), std::string::npos)
        << out.rejected[2];
    EXPECT_NE(out.rejected[3].find("outside [0, 1] or NaN"), std::string::npos) << out.rejected[3];
    EXPECT_NE(out.rejected[4].find("empty class name"), std::string::npos) << out.rejected[4];
  }
}

TEST(PluginHost, NewerPluginsLargerDetectionsAreSteppedBySize) {
  // A plugin built against a header with fields appended to emf_detection: the host steps by
  // its struct_size (by sizeof(emf_detection) it would read the second entry's class_name from
  // the first one's appended fields and crash).
  auto p = DetectorPlugin::load("test_newer", kTestPath, "", "", smallCamera());
  const DetectorOutput out = p->detect(frame(0, "1.000000"));
  EXPECT_TRUE(out.error.empty()) << out.error;
  ASSERT_EQ(out.detections.size(), 2u);
  EXPECT_EQ(out.detections[0].class_name, "cup");
  EXPECT_FLOAT_EQ(out.detections[0].score, 0.9f);
  EXPECT_EQ(out.detections[0].box, cv::Rect(20, 10, 30, 20));
  EXPECT_EQ(out.detections[1].class_name, "car");
  EXPECT_FLOAT_EQ(out.detections[1].score, 0.7f);
  EXPECT_EQ(out.detections[1].box, cv::Rect(30, 10, 30, 20));
  ASSERT_EQ(out.rejected.size(), 1u);
  EXPECT_NE(out.rejected[0].find("detection 2: struct_size 64 differs from detections[0]'s"),
            std::string::npos)
      << out.rejected[0];
}

TEST(PluginHost, NewObjectsOnlyFlagIsReadWhenTheStructHasIt) {
  // Flag set and the struct covers it: read; the malformed plugin does not set it; a plugin
  // reporting the struct_size from before the flags field sets it in memory past its struct:
  // the host must not read it.
  EXPECT_TRUE(
      DetectorPlugin::load("test_newonly", kTestPath, "", "", smallCamera())->newObjectsOnly());
  EXPECT_FALSE(
      DetectorPlugin::load("test_malformed", kTestPath, "", "", smallCamera())->newObjectsOnly());
  auto old = DetectorPlugin::load("test_oldapi", kTestPath, "", "", smallCamera());
  EXPECT_FALSE(old->newObjectsOnly());
  EXPECT_FALSE(old->detect(frame(0, "1.000000")).new_objects_only);
  auto p = DetectorPlugin::load("test_newonly", kTestPath, "", "", smallCamera());
  const DetectorOutput out = p->detect(frame(0, "1.000000"));
  EXPECT_TRUE(out.new_objects_only);
  EXPECT_EQ(out.detections.size(), 1u);  // otherwise the malformed plugin's results
  // The shipped motion plugin only proposes what the SLAM does not explain, from its feedback.
  auto motion = DetectorPlugin::load("motion", kBuildPath, "", "", smallCamera());
  EXPECT_TRUE(motion->newObjectsOnly());
  EXPECT_TRUE(motion->readsFeedback());
  // READS_FEEDBACK: not set by test_newonly; assumed for a plugin without the flags field.
  EXPECT_FALSE(
      DetectorPlugin::load("test_newonly", kTestPath, "", "", smallCamera())->readsFeedback());
  EXPECT_TRUE(old->readsFeedback());
}

// ---- maskfile ------------------------------------------------------------------------------

void writeMasks(const std::string& dir, const std::string& stamp) {
  std::filesystem::create_directories(dir + "/masks");
  cv::Mat ids(60, 80, CV_16U, cv::Scalar(0));
  ids(cv::Rect(5, 6, 10, 12)).setTo(1);
  ids(cv::Rect(40, 30, 20, 5)).setTo(2);
  ASSERT_TRUE(cv::imwrite(dir + "/masks/" + stamp + ".png", ids));
  std::ofstream(dir + "/masks/" + stamp + ".txt") << "1 teddy_bear 0.875\n2 car 0.5\n";
}

TEST(MaskfilePlugin, ReplaysStoredDetections) {
  const std::string dir = test::tempDir("maskfile");
  writeMasks(dir, "12.345678");
  auto p = DetectorPlugin::load("maskfile", kBuildPath, "", "tum:" + dir + "?depth_scale=1000",
                                smallCamera());
  EXPECT_EQ(p->name(), "maskfile");
  const DetectorOutput out = p->detect(frame(7, "12.345678"));
  ASSERT_TRUE(out.error.empty()) << out.error;
  ASSERT_EQ(out.detections.size(), 2u);
  EXPECT_EQ(out.detections[0].class_name, "teddy bear");
  EXPECT_FLOAT_EQ(out.detections[0].score, 0.875f);
  EXPECT_EQ(out.detections[0].box, cv::Rect(5, 6, 10, 12));
  EXPECT_DOUBLE_EQ(cv::sum(out.detections[0].mask)[0], 120.0);
  EXPECT_EQ(out.detections[1].class_name, "car");
  EXPECT_EQ(out.detections[1].box, cv::Rect(40, 30, 20, 5));
  // A frame without stored masks has no detections and no error.
  const DetectorOutput none = p->detect(frame(8, "12.400000"));
  EXPECT_TRUE(none.error.empty());
  EXPECT_TRUE(none.detections.empty());
}

TEST(MaskfilePlugin, ExplicitDirAndErrors) {
  const std::string dir = test::tempDir("maskfile-err");
  writeMasks(dir, "1.000000");
  std::ofstream(dir + "/masks/2.000000.txt") << "1 cup 0.5\nbroken line\n";
  cv::imwrite(dir + "/masks/2.000000.png", cv::Mat(60, 80, CV_16U, cv::Scalar(1)));
  std::ofstream(dir + "/masks/3.000000.txt") << "1 cup 0.5\n";
  cv::imwrite(dir + "/masks/3.000000.png", cv::Mat(30, 40, CV_16U, cv::Scalar(1)));
  auto p = DetectorPlugin::load("maskfile", kBuildPath, "dir=" + dir, "", smallCamera());
  EXPECT_EQ(p->detect(frame(0, "1.000000")).detections.size(), 2u);
  const DetectorOutput bad_line = p->detect(frame(1, "2.000000"));
  EXPECT_NE(bad_line.error.find("2.000000.txt:2"), std::string::npos) << bad_line.error;
  const DetectorOutput bad_size = p->detect(frame(2, "3.000000"));
  EXPECT_NE(bad_size.error.find("is 40x30, the depth image is 80x60"), std::string::npos)
      << bad_size.error;
  const std::string e = loadError("maskfile", kBuildPath);
  EXPECT_NE(e.find("no dataset folder"), std::string::npos) << e;
}

TEST(MaskfilePlugin, ReadsWhatTheDatasetReaderReadsAndRefusesWhatItRefuses) {
  // The folder comes percent-encoded in an upper-case scheme (emf's URI parser decodes both), and
  // the list has an indented comment, CRLF ends and a blank CR line, all of which the dataset
  // reader accepts: the plugin used to find no folder or reject every file.
  const std::string dir = test::tempDir("mask file");
  writeMasks(dir, "5.000000");
  std::ofstream(dir + "/masks/5.000000.txt", std::ios::binary)
      << "  # det_id class score\r\n1 teddy_bear 0.875\r\n\r\n\t2 car 0.5\r\n";
  std::string encoded = dir;
  encoded.replace(encoded.find("mask file"), 9, "mask%20file");
  auto p = DetectorPlugin::load("maskfile", kBuildPath, "", "TUM:" + encoded + "?depth_scale=1000",
                                smallCamera());
  const DetectorOutput out = p->detect(frame(0, "5.000000"));
  ASSERT_TRUE(out.error.empty()) << out.error;
  ASSERT_EQ(out.detections.size(), 2u);
  EXPECT_EQ(out.detections[0].class_name, "teddy bear");
  EXPECT_FLOAT_EQ(out.detections[0].score, 0.875f);
  EXPECT_EQ(out.detections[1].box, cv::Rect(40, 30, 20, 5));
  // What the dataset reader refuses, the plugin refuses, naming the line.
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"1 cup 0.5\n1 car 0.5\n", ".txt:2: detection id 1 is listed twice (also on line 1)"},
      {"1 cup 1.5\n", ".txt:1: expected `det_id class_name score`"},
      {"1 cup 0.5 extra\n", ".txt:1: expected"},
      {"1x cup 0.5\n", ".txt:1: expected"}};
  for (const auto& [text, expected] : bad) {
    std::ofstream(dir + "/masks/5.000000.txt") << text;
    const DetectorOutput r = p->detect(frame(1, "5.000000"));
    EXPECT_NE(r.error.find(expected), std::string::npos) << text << " -> " << r.error;
  }
}

}  // namespace
}  // namespace emf::pipeline
