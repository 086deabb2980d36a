// The output folder of `emf run`: claimed before the first frame, one run at a time, an earlier
// run's outputs replaced only when asked, leftovers of a killed write removed.
#include "pipeline/run_folder.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <regex>

#include "common/error.h"
#include "test_support.h"

namespace emf::pipeline {
namespace {

namespace fs = std::filesystem;

void touch(const std::string& path, const std::string& text = "old\n") {
  std::ofstream(path) << text;
}

TEST(RunFolder, CreatesTheFolderAndNamesTheRun) {
  const std::string dir = test::tempDir("runfolder-new") + "/a/b";
  const RunFolder f(dir, false);
  EXPECT_TRUE(fs::is_directory(dir));
  EXPECT_TRUE(std::regex_match(f.runId(), std::regex("[0-9]{8}T[0-9]{6}Z-[0-9]+"))) << f.runId();
  EXPECT_TRUE(std::regex_match(f.startedUtc(), std::regex("[0-9]{4}-[0-9]{2}-[0-9]{2}T[0-9:]{8}Z")))
      << f.startedUtc();
  EXPECT_EQ(f.path("camera.txt"), dir + "/camera.txt");
}

TEST(RunFolder, AFolderUnderAFileIsAnErrorNamingOut) {
  const std::string dir = test::tempDir("runfolder-file");
  touch(dir + "/file");
  try {
    const RunFolder f(dir + "/file/out", false);
    FAIL() << "no error";
  } catch (const IoError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(dir + "/file/out"), std::string::npos) << m;
    EXPECT_NE(m.find("--out"), std::string::npos) << m;
  }
}

TEST(RunFolder, AnEarlierRunIsAnErrorWithoutReplaceAndRemovedWithIt) {
  const std::string dir = test::tempDir("runfolder-earlier");
  touch(dir + "/run.json",
        R"({"run_id": "20260101T000000Z-7", "status": "finished", "frames": 40})");
  for (const char* name : {"camera.txt", "background.ply", "object-3.txt", "object-12.ply",
                           "eval.json", "notes.txt", "object-3.txt.bak"}) {
    touch(dir + "/" + name);
  }
  fs::create_directories(dir + "/images");
  touch(dir + "/images/000000-objects.png");
  try {
    const RunFolder f(dir, false);
    FAIL() << "no error";
  } catch (const IoError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("20260101T000000Z-7 (finished, 40 frames)"), std::string::npos) << m;
    EXPECT_NE(m.find("--force"), std::string::npos) << m;
  }
  EXPECT_TRUE(fs::exists(dir + "/camera.txt"));  // nothing removed without replace
  const RunFolder f(dir, true);
  for (const char* name : {"run.json", "camera.txt", "background.ply", "object-3.txt",
                           "object-12.ply", "eval.json", "images"}) {
    EXPECT_FALSE(fs::exists(dir + "/" + name)) << name;
  }
  // Files emf does not write stay.
  EXPECT_TRUE(fs::exists(dir + "/notes.txt"));
  EXPECT_TRUE(fs::exists(dir + "/object-3.txt.bak"));
  EXPECT_EQ(f.removed().size(), 7u);
}

TEST(RunFolder, TemporariesOfAKilledWriteAreRemoved) {
  const std::string dir = test::tempDir("runfolder-tmp");
  touch(dir + "/background.ply.tmp-4242-0");
  touch(dir + "/unrelated.tmp");
  const RunFolder f(dir, false);  // only temporaries: not an earlier run's outputs
  EXPECT_FALSE(fs::exists(dir + "/background.ply.tmp-4242-0"));
  EXPECT_TRUE(fs::exists(dir + "/unrelated.tmp"));
  ASSERT_EQ(f.removed().size(), 1u);
  EXPECT_EQ(f.removed()[0], "background.ply.tmp-4242-0");
}

TEST(RunFolder, ASecondWriterIsRefusedWhileTheFirstHoldsIt) {
  const std::string dir = test::tempDir("runfolder-lock");
  {
    const RunFolder first(dir, false);
    try {
      const RunFolder second(dir, true);
      FAIL() << "no error";
    } catch (const IoError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("another emf run (pid " + std::to_string(getpid()) + ")"), std::string::npos)
          << m;
    }
  }
  // Released with the first: the folder can be claimed again.
  EXPECT_NO_THROW(RunFolder(dir, false));
}

TEST(RunFolder, NamesOfOutputsAndTemporaries) {
  for (const char* name : {"run.json", "camera.txt", "background.ply", "object-1.txt",
                           "object-77.ply", "images", "eval.json", "eval.png"}) {
    EXPECT_TRUE(RunFolder::isRunOutput(name)) << name;
  }
  for (const char* name : {"object-.txt", "object-1.txt.bak", "camera.txt.tmp-1-2", "notes.txt",
                           ".emf-run.lock", "groundtruth.txt"}) {
    EXPECT_FALSE(RunFolder::isRunOutput(name)) << name;
  }
  EXPECT_TRUE(RunFolder::isTemporary("camera.txt.tmp-123-4"));
  EXPECT_FALSE(RunFolder::isTemporary("camera.tmp"));
  EXPECT_FALSE(RunFolder::isTemporary("x.tmp-12"));
}

}  // namespace
}  // namespace emf::pipeline
