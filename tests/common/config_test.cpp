#include "pipeline/config.h"

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <set>

#include "common/error.h"
#include "test_support.h"

namespace emf {
namespace {

std::string errorOf(const std::string& yaml, const std::string& origin = "test.yaml") {
  try {
    Config::loadString(yaml, origin);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(Config, DefaultsMatchMethod) {
  const Config c;
  EXPECT_DOUBLE_EQ(c.em.sigma_m, 0.02);
  EXPECT_DOUBLE_EQ(c.em.alpha, 0.8);
  EXPECT_DOUBLE_EQ(c.em.p_uniform, 1.0);
  EXPECT_DOUBLE_EQ(c.map.truncation_voxels, 10.0);
  EXPECT_DOUBLE_EQ(c.map.max_weight, 64.0);
  EXPECT_EQ(c.track.max_iterations, 100);
  EXPECT_DOUBLE_EQ(c.preprocess.sigma_depth_m, 0.04);
  EXPECT_DOUBLE_EQ(c.preprocess.sigma_space_px, 4.5);
  EXPECT_EQ(c.detector.every_n_frames, 30);
  EXPECT_DOUBLE_EQ(c.objects.match_iou, 0.2);
  EXPECT_EQ(c.objects.resolution, 64);
  EXPECT_NO_THROW(c.validate());
}

TEST(Config, LoadsValuesAndKeepsOthersAtDefault) {
  const Config c = Config::loadString("map:\n  memory_mb: 128\nem:\n  alpha: 0.5\n", "t.yaml");
  EXPECT_EQ(c.map.memory_mb, 128);
  EXPECT_DOUBLE_EQ(c.em.alpha, 0.5);
  EXPECT_DOUBLE_EQ(c.em.sigma_m, 0.02);
}

TEST(Config, UnknownKeyNamesFileLineKeyAndSuggestion) {
  const std::string e = errorOf("map:\n  memory_mb: 64\n  truncaton_voxels: 8\n", "room.yaml");
  EXPECT_NE(e.find("room.yaml:3"), std::string::npos) << e;
  EXPECT_NE(e.find("map.truncaton_voxels"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean 'map.truncation_voxels'"), std::string::npos) << e;
}

TEST(Config, UnknownSectionSuggestsClosest) {
  const std::string e = errorOf("tracking:\n  max_iterations: 3\n");
  EXPECT_NE(e.find("unknown section 'tracking'"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean 'track'"), std::string::npos) << e;
}

TEST(Config, WrongCaseSuggestsTheKeyItself) {
  const std::string e = errorOf("MAP:\n  memory_mb: 3\n");
  EXPECT_NE(e.find("did you mean 'map'"), std::string::npos) << e;
  const std::string k = errorOf("map:\n  Memory_MB: 3\n");
  EXPECT_NE(k.find("did you mean 'map.memory_mb'"), std::string::npos) << k;
}

TEST(Config, DuplicateKeysAndSectionsAreErrorsNamingBothLines) {
  // yaml-cpp keeps the first of two equal keys: the later one would be dropped silently.
  const std::string k = errorOf("map:\n  memory_mb: 100\n  memory_mb: 200\n", "d.yaml");
  EXPECT_NE(k.find("d.yaml:3: 'map.memory_mb' is given twice (first at d.yaml:2)"),
            std::string::npos)
      << k;
  const std::string s = errorOf(
      "map:\n  memory_mb: 64\ntrack:\n  pixel_stride: 1\nmap:\n"
      "  memory_mb: 128\n",
      "d.yaml");
  EXPECT_NE(s.find("d.yaml:5: 'map' is given twice (first at d.yaml:1)"), std::string::npos) << s;
}

TEST(Config, OutOfRangeNamesRange) {
  const std::string e = errorOf("em:\n  alpha: 1.5\n");
  EXPECT_NE(e.find("em.alpha"), std::string::npos) << e;
  EXPECT_NE(e.find("out of range [0, 1]"), std::string::npos) << e;
  const std::string e2 = errorOf("map:\n  memory_mb: 0\n");
  EXPECT_NE(e2.find("[1, 8191] MiB"), std::string::npos) << e2;
}

TEST(Config, WrongTypeIsAnError) {
  EXPECT_NE(errorOf("em:\n  alpha: high\n").find("expected a number"), std::string::npos);
  EXPECT_NE(errorOf("track:\n  max_iterations: 2.5\n").find("expected an integer"),
            std::string::npos);
  EXPECT_NE(errorOf("output:\n  binary_ply: maybe\n").find("expected true or false"),
            std::string::npos);
  EXPECT_NE(errorOf("cl:\n  device_type: gpuu\n").find("did you mean 'gpu'"), std::string::npos);
  EXPECT_NE(errorOf("em:\n  alpha: .nan\n").find("expected a number"), std::string::npos);
  EXPECT_NE(errorOf("map: [1, 2]\n").find("must be a mapping"), std::string::npos);
  EXPECT_NE(errorOf("map:\n  memory_mb: [\n").find("not valid YAML"), std::string::npos);
}

TEST(Config, SetOverridesOneKey) {
  Config c;
  c.set("map.memory_mb=32");
  EXPECT_EQ(c.map.memory_mb, 32);
  c.set("cl.device=pthread");
  EXPECT_EQ(c.cl.device, "pthread");
  EXPECT_THROW(c.set("map.memory_mb"), ConfigError);
  EXPECT_THROW(c.set("map.memry_mb=3"), ConfigError);
  // The message names the assignment, without the line of the document it is parsed as.
  try {
    c.set("map.memory_mb=0");
    ADD_FAILURE() << "memory_mb 0 accepted";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--set map.memory_mb=0: map.memory_mb: value 0 is out "
                                          "of range",
                                          0),
              0u)
        << e.what();
  }
}

TEST(Config, ChoicesAreReadIntoTheirEnums) {
  Config c;
  c.set("track.rotation_centre=origin");
  c.set("track.step_acceptance=fixed_weights");
  c.set("track.final_reduction=device");
  c.set("em.association=pfg");
  c.set("detector.mode=async");
  c.set("detector.isolation=none");
  EXPECT_EQ(c.track.rotation_centre, track::RotationCentre::kOrigin);
  EXPECT_EQ(c.track.step_acceptance, track::StepAcceptance::kFixedWeights);
  EXPECT_EQ(c.track.final_reduction, track::FinalReduction::kDevice);
  EXPECT_EQ(c.em.association, em::Association::kPfg);
  EXPECT_EQ(c.detector.mode, pipeline::DetectorMode::kAsync);
  EXPECT_EQ(c.detector.isolation, pipeline::DetectorIsolation::kNone);
  // Written back as their key texts.
  const Config back = Config::loadString(c.toYaml(), "round trip");
  EXPECT_EQ(back.track.rotation_centre, track::RotationCentre::kOrigin);
  EXPECT_EQ(back.detector.isolation, pipeline::DetectorIsolation::kNone);
  EXPECT_NE(c.toYaml().find("step_acceptance: fixed_weights"), std::string::npos);
  // A text that is not a choice names the key and the valid ones.
  for (const char* bad :
       {"detector.mode=sometimes", "track.rotation_centre=volume", "track.final_reduction=gpu"}) {
    try {
      c.set(bad);
      ADD_FAILURE() << bad << " accepted";
    } catch (const ConfigError& e) {
      const std::string key = std::string(bad).substr(0, std::string(bad).find('='));
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(c.detector.mode, pipeline::DetectorMode::kAsync);
}

TEST(Config, ValidateCatchesProgrammaticErrors) {
  Config c;
  c.em.alpha = -0.1;
  EXPECT_THROW(c.validate(), ConfigError);
}

TEST(Config, YamlRoundTrip) {
  Config c;
  c.map.memory_mb = 77;
  c.objects.exclude_classes = {"a b", "c"};
  const Config d = Config::loadString(c.toYaml(), "roundtrip");
  EXPECT_EQ(d.map.memory_mb, 77);
  EXPECT_EQ(d.objects.exclude_classes, c.objects.exclude_classes);
  EXPECT_EQ(d.toYaml(), c.toYaml());
}

TEST(Config, EditDistance) {
  EXPECT_EQ(editDistance("kitten", "sitting"), 3);
  EXPECT_EQ(editDistance("", "abc"), 3);
  EXPECT_EQ(editDistance("same", "same"), 0);
}

// conf/default.yaml must document every key with its default value, and nothing else.
TEST(Config, DefaultYamlDocumentsEveryKeyWithItsDefault) {
  const std::string path = std::string(EMF_SOURCE_DIR) + "/conf/default.yaml";
  const Config loaded = Config::loadFile(path);  // also rejects unknown keys
  EXPECT_EQ(loaded.toYaml(), Config().toYaml()) << "conf/default.yaml values differ from defaults";
  const YAML::Node root = YAML::LoadFile(path);
  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const auto& o : listOptions()) {
    EXPECT_TRUE(root[o.section] && root[o.section][o.key])
        << "conf/default.yaml lacks " << o.section << "." << o.key;
  }
}

TEST(Config, EveryPresetInConfLoads) {
  int count = 0;
  for (const auto& e : std::filesystem::directory_iterator(std::string(EMF_SOURCE_DIR) + "/conf")) {
    if (e.path().extension() != ".yaml") continue;
    EXPECT_NO_THROW(Config::loadFile(e.path().string())) << e.path();
    ++count;
  }
  EXPECT_GE(count, 1);
}

TEST(Config, MissingFileNamesIt) {
  try {
    Config::loadFile("/nonexistent/emf.yaml");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/emf.yaml"), std::string::npos);
  }
  // A folder opens as an empty stream: it must not pass as an empty configuration.
  const std::string dir = test::tempDir("config-folder");
  try {
    Config::loadFile(dir);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("is a folder, not a configuration file"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace emf
