// `emf synth`: writes a TUM folder, clear usage errors for bad presets and flags, refuses to
// overwrite a non-empty folder unless --force.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "test_support.h"

namespace emf {
namespace {
namespace fs = std::filesystem;

std::string cli() { return std::string(EMF_CLI_PATH); }

int countLines(const std::string& path) {
  std::ifstream in(path);
  int n = 0;
  std::string line;
  while (std::getline(in, line)) n += !line.empty() && line[0] != '#';
  return n;
}

TEST(CliSynth, WritesATumFolder) {
  const std::string out = test::tempDir("cli-synth") + "/cars";
  std::string log;
  ASSERT_EQ(test::runCommand(cli() + " synth cars --out " + out +
                                 " --frames 4 --width 64 --height 48 --seed 9 --det-every 2",
                             &log),
            0)
      << log;
  EXPECT_NE(log.find("emf synth: cars: 4/4 frames"), std::string::npos) << log;
  EXPECT_NE(log.find("wrote 4 frames of 'cars' (64x48, seed 9)"), std::string::npos) << log;
  EXPECT_EQ(countLines(out + "/rgb.txt"), 4);
  EXPECT_EQ(countLines(out + "/associations.txt"), 4);
  EXPECT_EQ(countLines(out + "/groundtruth.txt"), 4);
  EXPECT_EQ(countLines(out + "/objects/gt-object-1-world.txt"), 4);
  EXPECT_TRUE(fs::exists(out + "/masks/0.000000.txt"));
  EXPECT_TRUE(fs::exists(out + "/masks/0.066667.png"));
  EXPECT_FALSE(fs::exists(out + "/masks/0.033333.png"));
  std::ifstream readme(out + "/README.md");
  const std::string text((std::istreambuf_iterator<char>(readme)),
                         std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("emf synth cars --frames 4 --seed 9 --width 64 --height 48 --det-every 2"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("Two toy cars"), std::string::npos);
  EXPECT_NE(text.find("1 = car, 2 = car"), std::string::npos);

  // A non-empty folder is refused, then replaced with --force.
  EXPECT_EQ(test::runCommand(
                cli() + " synth room --out " + out + " --frames 2 --width 32 --height 24", &log),
            1);
  EXPECT_NE(log.find("is not empty"), std::string::npos) << log;
  EXPECT_NE(log.find("--force"), std::string::npos) << log;
  ASSERT_EQ(test::runCommand(cli() + " synth room --out " + out +
                                 " --frames 2 --width 32 --height 24 --force --no-noise",
                             &log),
            0)
      << log;
  ASSERT_EQ(test::runCommand(cli() + " synth room --out " + out +
                                 " --frames 2 --width 32 --height 24 --force --noise-without "
                                 "shadow,edges",
                             &log),
            0)
      << log;
  {
    std::ifstream again(out + "/README.md");
    const std::string about((std::istreambuf_iterator<char>(again)),
                            std::istreambuf_iterator<char>());
    EXPECT_NE(about.find("--det-every 30 --noise-without shadow,edges"), std::string::npos)
        << about;
    EXPECT_NE(about.find("Parts of the depth noise switched off: shadow,edges."), std::string::npos)
        << about;
  }
  EXPECT_EQ(countLines(out + "/rgb.txt"), 2);
  EXPECT_FALSE(fs::exists(out + "/objects/gt-object-1-world.txt"));  // room has no objects
  EXPECT_FALSE(fs::exists(out + "/depth/0.100000.png"));             // old frames are gone
}

TEST(CliSynth, UsageErrors) {
  const std::string out = test::tempDir("cli-synth-bad") + "/x";
  std::string log;
  EXPECT_EQ(test::runCommand(cli() + " synth kitchen --out " + out, &log), 2);
  EXPECT_NE(log.find("unknown preset 'kitchen': valid presets are room, cars, occlusion, enter, "
                     "apartment, and random"),
            std::string::npos)
      << log;
  EXPECT_EQ(test::runCommand(cli() + " synth room", &log), 2);
  EXPECT_NE(log.find("--out DIR is required"), std::string::npos) << log;
  EXPECT_EQ(test::runCommand(cli() + " synth room --out " + out + " --frames ten", &log), 2);
  EXPECT_NE(log.find("--frames ten: expected an integer in [1, 10000000]"), std::string::npos)
      << log;
  EXPECT_EQ(test::runCommand(cli() + " synth room --out " + out + " --width 4", &log), 2);
  EXPECT_NE(log.find("--width 4: expected an integer in [8, 8192]"), std::string::npos) << log;
  EXPECT_EQ(test::runCommand(cli() + " synth room --out " + out + " --colour", &log), 2);
  EXPECT_NE(log.find("unknown option --colour"), std::string::npos) << log;
  EXPECT_EQ(
      test::runCommand(cli() + " synth room --out " + out + " --noise-without axial,tilt", &log),
      2);
  EXPECT_NE(log.find("--noise-without axial,tilt: unknown part 'tilt': valid parts are axial, "
                     "quantization, edges, shadow, grazing, dropouts, range"),
            std::string::npos)
      << log;
  EXPECT_EQ(test::runCommand(
                cli() + " synth room --out " + out + " --noise-without axial --no-noise", &log),
            2);
  EXPECT_NE(log.find("--noise-without and --no-noise exclude each other"), std::string::npos)
      << log;
  EXPECT_EQ(test::runCommand(cli() + " synth --help", &log), 0);
  EXPECT_NE(log.find("usage: emf synth"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace emf
