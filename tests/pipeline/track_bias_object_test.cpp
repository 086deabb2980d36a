// bench/track_bias --object (the object tracker's floor on exact, object-only frames with a
// perfect history) end to end: it places the object's volume, tracks every frame the toy car is
// in, and its ATE follows the frames' noise (the bench's figures: docs/benchmarks.md).
#include <regex>

#include "test_support.h"

namespace emf {
namespace {

// Car 2 of `cars`, 30 frames at 320x240 (measured: 4.0 mm without noise, 20.8 mm with it).
constexpr double kExactFramesMaxAteMm = 8.0;
constexpr double kNoisyOverExactMinRatio = 2.5;

struct OracleRun {
  int tracked = 0, lost = 0;
  double ate_mm = 0;
};

OracleRun runOracle(bool noise) {
  std::string log;
  const std::string uri = std::string("'synth:cars?frames=30&width=320&height=240&noise=") +
                          (noise ? "true" : "false") + "'";
  const int code =
      test::runCommand(std::string(EMF_TRACK_BIAS_PATH) + " --data " + uri + " --object 2", &log);
  EXPECT_EQ(code, 0) << log;
  OracleRun r;
  std::smatch m;
  if (!std::regex_search(log, m, std::regex(R"(\(([0-9]+) tracked, ([0-9]+) lost\))"))) {
    ADD_FAILURE() << "no tracked/lost count in: " << log;
    return r;
  }
  r.tracked = std::stoi(m[1].str());
  r.lost = std::stoi(m[2].str());
  if (!std::regex_search(log, m, std::regex(R"(object=2 .* ate_mm=([0-9.]+))"))) {
    ADD_FAILURE() << "no machine-readable line in: " << log;
    return r;
  }
  r.ate_mm = std::stod(m[1].str());
  return r;
}

TEST(TrackBiasObject, TracksTheToyCarAndItsErrorFollowsTheNoise) {
  const OracleRun exact = runOracle(false);
  const OracleRun noisy = runOracle(true);
  // Frames 0 and 1 only start the constant-velocity prediction.
  EXPECT_EQ(exact.tracked, 28);
  EXPECT_EQ(exact.lost, 0);
  EXPECT_EQ(noisy.lost, 0);
  EXPECT_GT(exact.ate_mm, 0.0);
  EXPECT_LT(exact.ate_mm, kExactFramesMaxAteMm);
  EXPECT_GT(noisy.ate_mm, kNoisyOverExactMinRatio * exact.ate_mm);
}

TEST(TrackBiasObject, NamesTheFrameWithoutObjectGroundTruth) {
  const std::string data = test::tempDir("track_bias_object_tum");
  std::string log;
  // A TUM folder has no instance ids: the object mode needs a synthetic source.
  ASSERT_EQ(test::runCommand(std::string(EMF_CLI_PATH) + " synth room --frames 3 --width 160 " +
                                 "--height 120 --force --out " + data,
                             &log),
            0)
      << log;
  EXPECT_EQ(
      test::runCommand(std::string(EMF_TRACK_BIAS_PATH) + " --data " + data + " --object 1", &log),
      1);
  EXPECT_NE(log.find(data + ": frame 0 has no ground truth for object 1 (--object needs a "
                            "synth: source with that object)"),
            std::string::npos)
      << log;
}

}  // namespace
}  // namespace emf
