// The generated scenes (synth:random) over 60 seeds: every motion family, camera family, mover
// and still-object count drawn, sizes from a mug to a surfboard. Generating 60 scenes (each with
// its view checks) takes seconds in release and minutes under ASan: label slow.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "synth/random_scene.h"
#include "synth/scene.h"

namespace emf::synth {
namespace {

TEST(RandomScene, SeedsSpanEveryFamilyAndSize) {
  std::set<std::string> motions, cameras, classes;
  std::set<int> mover_counts, still_counts;
  double smallest = 1e9, largest = 0;
  for (uint64_t seed = 1; seed <= 60; ++seed) {
    const RandomScene r = makeRandomScene(seed, {});
    int movers = 0, still = 0;
    for (const auto& o : r.scene.objects) {
      std::string m = o.motion;
      for (size_t plus; (plus = m.find('+')) != std::string::npos; m = m.substr(plus + 1)) {
        motions.insert(m.substr(0, plus));
      }
      motions.insert(m);
      classes.insert(o.class_name);
      if (o.motion == "still") {
        ++still;
        continue;
      }
      ++movers;
      const double size = objectBounds(o).sizes().maxCoeff();
      smallest = std::min(smallest, size);
      largest = std::max(largest, size);
    }
    mover_counts.insert(movers);
    still_counts.insert(still);
    cameras.insert(r.scene.description.substr(r.scene.description.find("camera ") + 7, 5));
  }
  for (const char* m : {"drive", "spin", "rock", "wobble", "swing", "carry", "tumble", "push",
                        "float", "pass", "still"}) {
    EXPECT_TRUE(motions.count(m)) << m;
  }
  EXPECT_TRUE(cameras.count("sweep") && cameras.count("xyz a") && cameras.count("orbit"));
  EXPECT_TRUE(mover_counts.count(1) && mover_counts.count(2) && mover_counts.count(3));
  EXPECT_TRUE(still_counts.count(0) && still_counts.count(1) && still_counts.count(2));
  EXPECT_LE(smallest, 0.25);
  EXPECT_GE(largest, 1.0);
  EXPECT_GE(classes.size(), 10u);
}

}  // namespace
}  // namespace emf::synth
