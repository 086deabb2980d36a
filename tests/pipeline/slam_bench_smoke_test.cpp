// bench/slam_bench end to end without the peer (emf run as a child process on frames it wrote):
// the machine-readable line is printed and its emf ATE on the synthetic room is the real one.
#include <regex>

#include "test_support.h"

namespace emf {
namespace {

constexpr double kSynthRoomAteToleranceCm = 1.0;  // 12 frames, 320x240 @ 2 cm

TEST(SlamBench, PrintsTheEmfFiguresOfTheSyntheticRoom) {
  const std::string out = test::tempDir("slam_bench_smoke");
  std::string log;
  const int code =
      test::runCommand(std::string(EMF_SLAM_BENCH_PATH) +
                           " --no-peer --data synth --frames 12 --res 320 --out " + out,
                       &log);
  ASSERT_EQ(code, 0) << log;
  std::smatch m;
  const std::regex line(
      "slam_bench data=synth-room res=320x240 voxel_m=0.020 emf_ate_cm=([0-9.]+) emf_ms=([0-9.]+) "
      "emf_p90_ms=[0-9.]+ emf_lost=([0-9]+) .* peer_ate_cm=nan .* speedup=nan "
      "emf_vs_peer_ate_cm=nan gt_step_deg=nan emf_step_deg=nan peer_step_deg=nan");
  ASSERT_TRUE(std::regex_search(log, m, line)) << log;
  EXPECT_LT(std::stod(m[1].str()), kSynthRoomAteToleranceCm) << log;
  EXPECT_GT(std::stod(m[2].str()), 0.0);
  EXPECT_EQ(m[3].str(), "0") << log;
}

TEST(SlamBench, RejectsAnUnknownResolution) {
  std::string log;
  const int code =
      test::runCommand(std::string(EMF_SLAM_BENCH_PATH) + " --res 123 --no-peer", &log);
  EXPECT_EQ(code, 2) << log;  // a usage error
  EXPECT_NE(log.find("--res '123': use 640 (640x480@1cm) or 320 (320x240@2cm)"), std::string::npos)
      << log;
}

}  // namespace
}  // namespace emf
