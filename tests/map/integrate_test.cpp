// Block allocation and TSDF integration on the device (PoCL) against the CPU references, on
// analytic scenes and on a real Kinect frame.
#include <algorithm>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "map_fixture.h"

namespace emf::test {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

class Integration : public MapTest {};

/// Calls fn(voxel, pixel x, pixel y, camera-frame centre) for every allocated voxel of `h` whose
/// centre projects into the image (T_cv: volume frame -> camera frame).
template <typename Fn>
void forEachVoxelInView(const map::VolumeHostData& h, float voxel_size_m, const map::PoseRows& T_cv,
                        const core::Intrinsics& k, Fn fn) {
  for (size_t lin = 0; lin < h.index.size(); ++lin) {
    if (h.index[lin] < 0) continue;
    const Eigen::Vector3i base = map::blockCoords(h.dims_blocks, static_cast<int>(lin)) * 8;
    for (int n = 0; n < map::kBlockVoxels; ++n) {
      const Eigen::Vector3i vx = base + Eigen::Vector3i(n % 8, (n / 8) % 8, n / 64);
      const Eigen::Vector3f pc = T_cv.transform(map::voxelCentre(vx, voxel_size_m));
      int px, py;
      if (pc.z() <= 0 || !map::projectToPixel(pc, cameraF(k), &px, &py)) continue;
      fn(vx, px, py, pc);
    }
  }
}

TEST_F(Integration, AllocationMarksTheTruncationBandAsTheReference) {
  const map::MapOptions o = smallOptions();
  map::VoxelPool pool(ctx(), o);
  const map::VolumeSpec spec = map::VolumeSpec::background(o);
  const Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
  map::Volume vol(pool, spec, map::backgroundVolumePose(o, spec, T_wc));
  const core::Intrinsics k = testIntrinsics(320, 240);
  const Scene scene;
  Frame f = makeFrame(renderDepth(scene, k, T_wc), k, T_wc);
  const map::AllocationReport rep = vol.allocate(f.input);
  const map::VolumeHostData h = vol.download();
  const std::vector<uint8_t> marked = map::markBlocksReference(
      f.depth_host, cameraF(k), map::PoseRows::from(vol.T_world_volume().inverse() * T_wc),
      static_cast<float>(map::kBlockSize) * spec.voxel_size_m, spec.truncation_m, spec.dims_blocks);
  int expected = 0;
  for (size_t i = 0; i < marked.size(); ++i) {
    expected += marked[i];
    ASSERT_EQ(h.index[i] >= 0, marked[i] != 0) << "block " << i;
  }
  EXPECT_GT(expected, 100);
  EXPECT_EQ(rep.allocated_blocks, expected);
  EXPECT_EQ(rep.new_blocks, expected);
  EXPECT_EQ(rep.listed_blocks, expected);
  EXPECT_EQ(rep.dropped_blocks, 0);
  EXPECT_EQ(h.allocatedBlocks(), expected);
  const map::PoolStats s = pool.stats();
  EXPECT_EQ(s.used_slots, expected);
  EXPECT_EQ(s.free_slots, pool.capacitySlots() - expected);
  // Slots are distinct and were taken from the bottom of the free list: 0 .. expected-1.
  std::vector<int32_t> slots = h.pool_slots;
  std::sort(slots.begin(), slots.end());
  for (int i = 0; i < expected; ++i) ASSERT_EQ(slots[static_cast<size_t>(i)], i);

  // The same frame again allocates nothing new.
  const map::AllocationReport again = vol.allocate(f.input);
  EXPECT_EQ(again.new_blocks, 0);
  EXPECT_EQ(again.allocated_blocks, expected);
  EXPECT_EQ(again.listed_blocks, expected);
}

TEST_F(Integration, AllocationReachesTheLastBlockOfAGridOfAnyBlockCount) {
  // assign_blocks visits the flags in groups of 16 and skips unmarked groups: a grid of 5 x 7 x 3
  // = 105 blocks ends in a partial group, which holds the scratch flag too. A wall 1 m ahead
  // crosses the grid's last z-slab, whose far corner block (the last index) sits on the optical
  // axis: every marked block, that one included, gets its slot, for a volume that lists only the
  // marked blocks (background) and for one that lists all (object), on a second frame too.
  const map::MapOptions o = smallOptions();
  const core::Intrinsics k = testIntrinsics(160, 120);
  const Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
  constexpr float kWallM = 1.0f;
  Frame f = makeFrame(cv::Mat(k.height, k.width, CV_32F, cv::Scalar(kWallM)), k, T_wc);
  for (const bool object : {false, true}) {
    SCOPED_TRACE(object ? "object volume" : "background volume");
    map::VoxelPool pool(ctx(), o);
    map::VolumeSpec spec =
        object ? map::VolumeSpec::object(o, 64, 0.02f) : map::VolumeSpec::background(o);
    spec.dims_blocks = Eigen::Vector3i(5, 7, 3);
    const int n = spec.blockCount();
    ASSERT_NE(n % 16, 0);
    const double block_m = map::kBlockSize * static_cast<double>(spec.voxel_size_m);
    Eigen::Isometry3d T_wv = Eigen::Isometry3d::Identity();  // last block's centre on the axis
    T_wv.translation() = Eigen::Vector3d(0.0, 0.0, kWallM) -
                         (spec.dims_blocks.cast<double>().array() - 0.5).matrix() * block_m;
    map::Volume vol(pool, spec, T_wv);
    const std::vector<uint8_t> marked = map::markBlocksReference(
        f.depth_host, cameraF(k), map::PoseRows::from(T_wv.inverse() * T_wc),
        static_cast<float>(block_m), spec.truncation_m, spec.dims_blocks);
    const int expected = static_cast<int>(std::count(marked.begin(), marked.end(), 1));
    ASSERT_EQ(marked.back(), 1);
    for (int frame = 0; frame < 2; ++frame) {
      const map::AllocationReport rep = vol.allocate(f.input);
      const map::VolumeHostData h = vol.download();
      for (int i = 0; i < n; ++i) {
        ASSERT_EQ(h.index[static_cast<size_t>(i)] >= 0, marked[static_cast<size_t>(i)] != 0)
            << "block " << i << ", frame " << frame;
      }
      EXPECT_EQ(rep.allocated_blocks, expected);
      EXPECT_EQ(rep.new_blocks, frame == 0 ? expected : 0);
      EXPECT_EQ(rep.listed_blocks, expected);  // all allocated blocks are marked here
    }
  }
}

TEST_F(Integration, AllocationFromEveryNthPixelMarksTheReferencesBlocks) {
  // map.mark_stride 2: the device marks exactly the reference's blocks from every second pixel
  // in x and y, a subset of those of every pixel that misses only band slivers.
  map::MapOptions o = smallOptions();
  o.mark_stride = 2;
  map::VoxelPool pool(ctx(), o);
  const map::VolumeSpec spec = map::VolumeSpec::background(o);
  ASSERT_EQ(spec.mark_stride, 2);
  const Eigen::Isometry3d T_wc =
      lookAt(Eigen::Vector3d(0.4, -0.1, 0.2), Eigen::Vector3d(0.0, 0.3, 2.0));
  map::Volume vol(pool, spec, map::backgroundVolumePose(o, spec, Eigen::Isometry3d::Identity()));
  const core::Intrinsics k = testIntrinsics(320, 240);
  const Scene scene;
  Frame f = makeFrame(renderDepth(scene, k, T_wc), k, T_wc);
  const map::AllocationReport rep = vol.allocate(f.input);
  const map::VolumeHostData h = vol.download();
  const map::PoseRows T_vc = map::PoseRows::from(vol.T_world_volume().inverse() * T_wc);
  const float block_m = static_cast<float>(map::kBlockSize) * spec.voxel_size_m;
  const std::vector<uint8_t> every = map::markBlocksReference(
      f.depth_host, cameraF(k), T_vc, block_m, spec.truncation_m, spec.dims_blocks, 1);
  const std::vector<uint8_t> second = map::markBlocksReference(
      f.depth_host, cameraF(k), T_vc, block_m, spec.truncation_m, spec.dims_blocks, 2);
  int n_every = 0, n_second = 0;
  for (size_t i = 0; i < every.size(); ++i) {
    ASSERT_EQ(h.index[i] >= 0, second[i] != 0) << "block " << i;
    ASSERT_TRUE(every[i] || !second[i]) << "block " << i;
    n_every += every[i];
    n_second += second[i];
  }
  EXPECT_EQ(rep.listed_blocks, n_second);
  constexpr double kMinShare = 0.97;  // slivers of the band seen by odd pixels alone
  EXPECT_GE(n_second, kMinShare * n_every);
  EXPECT_LT(n_second, n_every);  // the scene has such slivers: the stride is in effect
}

TEST_F(Integration, AllocationOverTheGridsImageRectangleMarksTheSameBlocks) {
  // An object-sized grid (0.64 m) in front of the camera: allocation over the rectangle its box
  // projects to marks exactly the blocks of a whole-image pass; a rectangle cut in half fewer.
  const map::MapOptions o = smallOptions();
  map::VoxelPool pool(ctx(), o);
  const map::VolumeSpec spec = map::VolumeSpec::object(o, 64, 0.01f);
  const Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_wv = Eigen::Isometry3d::Identity();
  T_wv.translation() = Eigen::Vector3d(-0.5, -0.2, 1.2);
  const core::Intrinsics k = testIntrinsics(320, 240);
  const Scene scene;
  Frame f = makeFrame(renderDepth(scene, k, T_wc), k, T_wc);
  // The grid box's projection: bounding rectangle of its corners, one pixel wider.
  double u0 = 1e9, u1 = -1e9, v0 = 1e9, v1 = -1e9;
  const Eigen::Vector3d extent = spec.extentM().cast<double>();
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d p = T_wc.inverse() * T_wv *
                              Eigen::Vector3d((c & 1) ? extent.x() : 0, (c & 2) ? extent.y() : 0,
                                              (c & 4) ? extent.z() : 0);
    ASSERT_GT(p.z(), 0.1);
    u0 = std::min(u0, k.fx * p.x() / p.z() + k.cx);
    u1 = std::max(u1, k.fx * p.x() / p.z() + k.cx);
    v0 = std::min(v0, k.fy * p.y() / p.z() + k.cy);
    v1 = std::max(v1, k.fy * p.y() / p.z() + k.cy);
  }
  const cv::Rect image(0, 0, k.width, k.height);
  const cv::Rect grid_px =
      cv::Rect(
          cv::Point(static_cast<int>(std::floor(u0)) - 1, static_cast<int>(std::floor(v0)) - 1),
          cv::Point(static_cast<int>(std::ceil(u1)) + 2, static_cast<int>(std::ceil(v1)) + 2)) &
      image;
  ASSERT_LT(grid_px.area(), image.area() / 2);  // the rectangle leaves most pixels out

  map::Volume whole(pool, spec, T_wv), bounded(pool, spec, T_wv), halved(pool, spec, T_wv);
  const map::AllocationReport rw = whole.allocate(f.input);
  Frame fb = makeFrame(f.depth_host, k, T_wc);
  fb.input.pixels = grid_px;
  const map::AllocationReport rb = bounded.allocate(fb.input);
  fb.input.pixels = cv::Rect(grid_px.x, grid_px.y, grid_px.width / 2, grid_px.height);
  const map::AllocationReport rh = halved.allocate(fb.input);
  EXPECT_GT(rw.listed_blocks, 20);
  EXPECT_EQ(rb.listed_blocks, rw.listed_blocks);
  EXPECT_LT(rh.listed_blocks, rw.listed_blocks);
  const map::VolumeHostData hw = whole.download(), hb = bounded.download();
  ASSERT_EQ(hw.index.size(), hb.index.size());
  for (size_t i = 0; i < hw.index.size(); ++i) {
    ASSERT_EQ(hw.index[i] >= 0, hb.index[i] >= 0) << "block " << i;
  }
}

TEST_F(Integration, AllocationInARegionMarksTheWholeGridsBlocksThatMeetIt) {
  // The background-sized grid over the analytic scene: allocation limited to a box (volume
  // frame, metres) marks exactly those blocks of a whole-grid pass whose extent meets the box.
  const map::MapOptions o = smallOptions();
  map::VoxelPool pool(ctx(), o);
  const map::VolumeSpec spec = map::VolumeSpec::background(o);
  const Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
  const Eigen::Isometry3d T_wv = map::backgroundVolumePose(o, spec, T_wc);
  const core::Intrinsics k = testIntrinsics(320, 240);
  const Scene scene;
  Frame f = makeFrame(renderDepth(scene, k, T_wc), k, T_wc);
  map::Volume whole(pool, spec, T_wv), limited(pool, spec, T_wv);
  const map::AllocationReport rw = whole.allocate(f.input);
  // Half the grid's extent on x and y, centred; no bound on a block boundary.
  const Eigen::Vector3d extent = spec.extentM().cast<double>();
  const Eigen::AlignedBox3d region(
      Eigen::Vector3d(0.25 * extent.x() + 0.013, 0.25 * extent.y() + 0.011, 0.0),
      Eigen::Vector3d(0.75 * extent.x() - 0.017, 0.75 * extent.y() - 0.021, extent.z()));
  Frame fl = makeFrame(f.depth_host, k, T_wc);
  fl.input.region = region;
  const map::AllocationReport rl = limited.allocate(fl.input);
  const map::VolumeHostData hw = whole.download(), hl = limited.download();
  ASSERT_EQ(hw.index.size(), hl.index.size());
  const double block_m = map::kBlockSize * static_cast<double>(spec.voxel_size_m);
  int expected = 0;
  for (size_t i = 0; i < hw.index.size(); ++i) {
    const Eigen::Vector3d lo =
        map::blockCoords(spec.dims_blocks, static_cast<int>(i)).cast<double>() * block_m;
    const bool meets =
        !region.intersection(Eigen::AlignedBox3d(lo, lo + Eigen::Vector3d::Constant(block_m)))
             .isEmpty();
    const bool want = hw.index[i] >= 0 && meets;
    expected += want ? 1 : 0;
    ASSERT_EQ(hl.index[i] >= 0, want) << "block " << i;
  }
  EXPECT_GT(expected, 20);
  EXPECT_LT(expected, rw.listed_blocks);  // the region leaves blocks out
  EXPECT_EQ(rl.listed_blocks, expected);
}

TEST_F(Integration, PlainFusionMatchesReferenceOverSeveralViews) {
  const map::MapOptions o = smallOptions();
  map::VoxelPool pool(ctx(), o);
  const map::VolumeSpec spec = map::VolumeSpec::background(o);
  const Eigen::Isometry3d T_w0 = Eigen::Isometry3d::Identity();
  map::Volume vol(pool, spec, map::backgroundVolumePose(o, spec, T_w0));
  const core::Intrinsics k = testIntrinsics(320, 240);
  const Scene scene;
  const Eigen::Isometry3d poses[] = {
      T_w0, lookAt(Eigen::Vector3d(0.4, -0.1, 0.2), Eigen::Vector3d(0.0, 0.3, 2.0)),
      lookAt(Eigen::Vector3d(-0.3, 0.1, 0.5), Eigen::Vector3d(0.3, 0.2, 1.6))};
  for (const auto& T : poses) {
    Frame f = makeFrame(renderDepth(scene, k, T), k, T);
    EXPECT_EQ(fuseAndCompare(vol, f), 0);
  }
  // Weights: voxels seen in all three views near the sphere front have weight 3.
  const map::VolumeHostData h = vol.download();
  const map::VolumeHostView v = h.view();
  const Eigen::Vector3d front_w = scene.spheres[0].centre_w - Eigen::Vector3d(0, 0, 0.35);
  const Eigen::Vector3f p = (vol.T_world_volume().inverse() * front_w).cast<float>();
  float psi = 0, w = 0;
  Eigen::Vector3f g;
  ASSERT_TRUE(map::sampleSdfReference(v, p, &psi, &w, &g));
  EXPECT_NEAR(w, 3.0f, 1e-3f);
  EXPECT_NEAR(psi, 0.0f, 0.5f * spec.voxel_size_m);
}

TEST_F(Integration, AssociationWeightsAndFreeSpaceRuleMatchReference) {
  for (bool full_weight : {true, false}) {
    SCOPED_TRACE(full_weight ? "free_space_full_weight" : "free space weighted by q");
    map::MapOptions o = smallOptions();
    o.free_space_full_weight = full_weight;
    map::VoxelPool pool(ctx(), o);
    const map::VolumeSpec spec = map::VolumeSpec::background(o);
    const Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    map::Volume vol(pool, spec, map::backgroundVolumePose(o, spec, T));
    const core::Intrinsics k = testIntrinsics(320, 240);
    const Scene scene;
    // q: 0 on the left third, a ramp elsewhere.
    cv::Mat q(k.height, k.width, CV_32FC1);
    for (int y = 0; y < k.height; ++y) {
      for (int x = 0; x < k.width; ++x) {
        q.at<float>(y, x) = x < k.width / 3 ? 0.0f : static_cast<float>(x) / k.width;
      }
    }
    Frame f = makeFrame(renderDepth(scene, k, T), k, T, q);
    map::VolumeHostData h;
    EXPECT_EQ(fuseAndCompare(vol, f, &h), 0);
    // Semantics: in the left third, band voxels stay unobserved; free-space voxels (more than a
    // truncation in front of the surface) get weight 1 only with the authors' rule.
    const map::VolumeHostView v = h.view();
    int band = 0, free_full = 0, free_zero = 0;
    const map::PoseRows T_cv = map::PoseRows::from(T.inverse() * vol.T_world_volume());
    forEachVoxelInView(h, spec.voxel_size_m, T_cv, k,
                       [&](const Eigen::Vector3i& vx, int px, int py, const Eigen::Vector3f& pc) {
                         if (px >= k.width / 3 - 1) return;
                         const float sdf = f.depth_host.at<float>(py, px) - pc.z();
                         const map::Voxel& vox = h.voxels[static_cast<size_t>(v.voxelIndex(vx))];
                         if (std::abs(sdf) <= spec.truncation_m) {
                           ++band;
                           EXPECT_EQ(vox.weight_q, 0);
                         } else if (sdf > spec.truncation_m) {
                           (vox.weight_q == 256 ? free_full : free_zero)++;
                         }
                       });
    EXPECT_GT(band, 1000);
    if (full_weight) {
      EXPECT_GT(free_full, 100);
      EXPECT_EQ(free_zero, 0);
    } else {
      EXPECT_EQ(free_full, 0);
      EXPECT_GT(free_zero, 100);
    }
  }
}

TEST_F(Integration, BehindTheSurfaceDropOffMatchesReference) {
  // One frame into a background-sized volume with and without the drop-off: the device matches
  // the reference, and a voxel at projective distance d behind the surface (d < -voxel) holds
  // weight (truncation + d) / (truncation - voxel) instead of 1; in front of it weight 1 both ways.
  map::MapOptions o = smallOptions();
  map::VoxelPool pool(ctx(), o);
  const Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const core::Intrinsics k = testIntrinsics(320, 240);
  const Scene scene;
  Frame f = makeFrame(renderDepth(scene, k, T), k, T);
  constexpr double kWeightTolerance = 2.0 / 256.0;  // the stored weight's step, and rounding
  for (bool dropoff : {false, true}) {
    SCOPED_TRACE(dropoff ? "drop-off" : "full weight behind");
    map::VolumeSpec spec = map::VolumeSpec::background(o);
    spec.behind_dropoff = dropoff;
    map::Volume vol(pool, spec, map::backgroundVolumePose(o, spec, T));
    map::VolumeHostData h;
    EXPECT_EQ(fuseAndCompare(vol, f, &h), 0);
    const map::VolumeHostView v = h.view();
    const map::PoseRows T_cv = map::PoseRows::from(T.inverse() * vol.T_world_volume());
    int behind = 0, front = 0;
    double worst = 0.0;
    forEachVoxelInView(
        h, spec.voxel_size_m, T_cv, k,
        [&](const Eigen::Vector3i& vx, int px, int py, const Eigen::Vector3f& pc) {
          const float sdf = f.depth_host.at<float>(py, px) - pc.z();
          if (!(std::abs(sdf) < spec.truncation_m)) return;
          const double w = h.voxels[static_cast<size_t>(v.voxelIndex(vx))].weight_q / 256.0;
          double expected = 1.0;
          if (sdf < -spec.voxel_size_m) {
            ++behind;
            if (dropoff) {
              expected = (spec.truncation_m + sdf) / (spec.truncation_m - spec.voxel_size_m);
            }
          } else {
            ++front;
          }
          if (expected * 256.0 < 0.5) return;  // stored as 0: not updated
          worst = std::max(worst, std::abs(w - expected));
        });
    EXPECT_GT(behind, 1000);
    EXPECT_GT(front, 1000);
    EXPECT_LE(worst, kWeightTolerance);
  }
}

TEST_F(Integration, WeightCapAndRunningAverage) {
  map::MapOptions o = smallOptions();
  o.max_weight = 5;
  map::VoxelPool pool(ctx(), o);
  const map::VolumeSpec spec = map::VolumeSpec::background(o);
  const Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  map::Volume vol(pool, spec, map::backgroundVolumePose(o, spec, T));
  const core::Intrinsics k = testIntrinsics(160, 120);
  const Scene scene;
  Frame f = makeFrame(renderDepth(scene, k, T), k, T);
  map::VolumeHostData h;
  for (int i = 0; i < 7; ++i) ASSERT_EQ(fuseAndCompare(vol, f, &h, i == 0), 0) << "frame " << i;
  int capped = 0;
  for (const map::Voxel& v : h.voxels) {
    ASSERT_LE(v.weight_q, 5 * 256);
    capped += v.weight_q == 5 * 256;
  }
  EXPECT_GT(capped, 10000);
}

TEST_F(Integration, EveryNthFrameIntegratesEachBandBlockInItsPhase) {
  // map.integrate_every 2: the band's blocks are integrated on alternate frames in a 3-D
  // checkerboard ((x + y + z) mod 2 == the allocation's phase), each observation with weight 2;
  // a block that gets its slot is integrated at once. fuseAndCompare checks every voxel against
  // the reference's block list and weights.
  map::MapOptions o = smallOptions();
  o.integrate_every = 2;
  map::VoxelPool pool(ctx(), o);
  const map::VolumeSpec spec = map::VolumeSpec::background(o);
  ASSERT_EQ(spec.integrate_every, 2);
  const Eigen::Isometry3d T0 = Eigen::Isometry3d::Identity();
  map::Volume vol(pool, spec, map::backgroundVolumePose(o, spec, T0));
  const core::Intrinsics k = testIntrinsics(160, 120);
  const Scene scene;
  const Frame f0 = makeFrame(renderDepth(scene, k, T0), k, T0);
  map::VolumeHostData h;
  ASSERT_EQ(fuseAndCompare(vol, f0, &h), 0);
  const map::AllocationReport r0 = vol.lastReport();
  EXPECT_EQ(r0.phase, 0);
  EXPECT_EQ(r0.listed_blocks, r0.new_blocks);  // all new: all integrated
  ASSERT_EQ(fuseAndCompare(vol, f0, &h), 0);
  const map::AllocationReport r1 = vol.lastReport();
  EXPECT_EQ(r1.phase, 1);
  EXPECT_EQ(r1.new_blocks, 0);
  EXPECT_GT(r1.listed_blocks, r1.allocated_blocks * 35 / 100);
  EXPECT_LT(r1.listed_blocks, r1.allocated_blocks * 65 / 100);
  // The same view twice, each observation weighing 2: odd blocks hold weight 4 where the frame
  // observed them, even blocks 2.
  auto block_max_weight = [](const map::VolumeHostData& d, size_t lin) {
    int w = 0;
    const size_t base = static_cast<size_t>(d.index[lin]) * map::kBlockVoxels;
    for (int i = 0; i < map::kBlockVoxels; ++i) w = std::max<int>(w, d.voxels[base + i].weight_q);
    return w;
  };
  int odd = 0, even = 0;
  for (size_t lin = 0; lin < h.index.size(); ++lin) {
    if (h.index[lin] < 0) continue;
    const Eigen::Vector3i b = map::blockCoords(h.dims_blocks, static_cast<int>(lin));
    const bool is_odd = (b.x() + b.y() + b.z()) % 2 == 1;
    const int w = block_max_weight(h, lin);
    if (w == 0) continue;  // a marked block's corner may see no voxel centre
    ASSERT_EQ(w, is_odd ? 4 * 256 : 2 * 256) << "block " << lin;
    (is_odd ? odd : even)++;
  }
  EXPECT_GT(odd, 50);
  EXPECT_GT(even, 50);
  // A view that reveals new blocks (phase 0 again): the new odd blocks are integrated too.
  const Eigen::Isometry3d T1 =
      lookAt(Eigen::Vector3d(0.4, -0.1, 0.2), Eigen::Vector3d(0.0, 0.3, 2.0));
  const std::vector<int32_t> index_before = h.index;
  ASSERT_EQ(fuseAndCompare(vol, makeFrame(renderDepth(scene, k, T1), k, T1), &h), 0);
  EXPECT_EQ(vol.lastReport().phase, 0);
  EXPECT_GT(vol.lastReport().new_blocks, 10);
  int new_odd = 0, new_odd_observed = 0;
  for (size_t lin = 0; lin < h.index.size(); ++lin) {
    if (h.index[lin] < 0 || index_before[lin] >= 0) continue;
    const Eigen::Vector3i b = map::blockCoords(h.dims_blocks, static_cast<int>(lin));
    if ((b.x() + b.y() + b.z()) % 2 == 0) continue;
    ++new_odd;
    new_odd_observed += block_max_weight(h, lin) > 0;
  }
  EXPECT_GT(new_odd, 5);
  EXPECT_GE(new_odd_observed, new_odd * 9 / 10);  // a marked block's corner may see no voxel
}

TEST_F(Integration, AVolumesOwnWeightCapOverridesTheMaps) {
  // An object volume capped at 3 in a pool whose map.max_weight is 5 (objects.max_weight).
  map::MapOptions o = smallOptions();
  o.max_weight = 5;
  map::VoxelPool pool(ctx(), o);
  const Scene scene;
  map::VolumeSpec spec = map::VolumeSpec::object(o, 48, 0.02f);
  spec.max_weight = 3;
  Eigen::Isometry3d T_wv = Eigen::Isometry3d::Identity();
  T_wv.translation() = scene.spheres[1].centre_w - Eigen::Vector3d::Constant(0.48);
  map::Volume vol(pool, spec, T_wv);
  const core::Intrinsics k = testIntrinsics(160, 120);
  const Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  Frame f = makeFrame(renderDepth(scene, k, T), k, T);
  map::VolumeHostData h;
  // fuseAndCompare checks every voxel against the reference at the volume's own cap.
  for (int i = 0; i < 5; ++i) ASSERT_EQ(fuseAndCompare(vol, f, &h, i == 0), 0) << "frame " << i;
  int capped = 0;
  for (const int32_t slot : h.index) {  // TSDF blocks (the count blocks hold (Fg, Bg))
    if (slot < 0) continue;
    for (int i = 0; i < map::kBlockVoxels; ++i) {
      const map::Voxel& v = h.voxels[static_cast<size_t>(slot) * map::kBlockVoxels + i];
      ASSERT_LE(v.weight_q, 3 * 256);
      capped += v.weight_q == 3 * 256;
    }
  }
  EXPECT_GT(capped, 1000);
}

TEST_F(Integration, ForegroundCountsFromDetectionMaskMatchReference) {
  const map::MapOptions o = smallOptions();
  map::VoxelPool pool(ctx(), o);
  const Scene scene;
  const Sphere& s = scene.spheres[1];  // on the floor: the box holds floor too
  // Object volume of 48 voxels at 2 cm (0.96 m) centred on the sphere.
  map::VolumeSpec spec = map::VolumeSpec::object(o, 48, 0.02f);
  Eigen::Isometry3d T_wv = Eigen::Isometry3d::Identity();
  T_wv.translation() = s.centre_w - Eigen::Vector3d::Constant(0.48);
  map::Volume vol(pool, spec, T_wv);
  const core::Intrinsics k = testIntrinsics(320, 240);
  const Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const cv::Mat depth = renderDepth(scene, k, T);
  // Mask: 1 on the sphere, 0 elsewhere, NaN (occluded, no update) on a vertical strip.
  cv::Mat mask = sphereMask(scene, 1, k, T);
  mask.colRange(100, 104).setTo(kNaN);
  Frame f = makeFrame(depth, k, T, cv::Mat(), mask);
  map::VolumeHostData h;
  EXPECT_EQ(fuseAndCompare(vol, f, &h), 0);
  EXPECT_EQ(fuseAndCompare(vol, f, &h), 0);  // counts accumulate
  // Every allocated block has its count block; two slots per block.
  EXPECT_EQ(pool.stats().used_slots, 2 * h.allocatedBlocks());
  const map::VolumeHostView v = h.view();
  const Eigen::Vector3f front =
      (T_wv.inverse() * (s.centre_w - Eigen::Vector3d(0, 0, s.radius_m))).cast<float>();
  EXPECT_NEAR(map::samplePfgReference(v, front), 1.0f, 1e-6f);
  // Background behind the sphere's silhouette (wall / floor inside the object box) is 0.
  int fg = 0, bg = 0;
  for (int32_t cs : h.count_index) {
    if (cs < 0) continue;
    for (int n = 0; n < map::kBlockVoxels; ++n) {
      const Eigen::Vector2f c =
          map::counts(h.voxels[static_cast<size_t>(cs) * map::kBlockVoxels + n]);
      if (c.x() + c.y() == 0) continue;
      ASSERT_NEAR(c.x() + c.y(), 2.0f, 1e-6f) << "two observations, each Fg + Bg = 1";
      (c.x() > 0 ? fg : bg)++;
    }
  }
  EXPECT_GT(fg, 500);
  EXPECT_GT(bg, 500);
}

TEST_F(Integration, CountsHalveBeforeOverflowKeepingPfg) {
  map::Voxel c;
  int halvings = 0;
  float prev_sum = 0;
  for (int i = 0; i < 2000; ++i) {  // Fg alone reaches 65535 / 192 after 341 observations
    c = map::addCounts(c, 0.75f);
    const Eigen::Vector2f n = map::counts(c);
    halvings += n.x() + n.y() < prev_sum;
    prev_sum = n.x() + n.y();
    ASSERT_NEAR(map::pfgFromCounts(n.x(), n.y()), 0.75f, 2e-3f) << "observation " << i;
  }
  EXPECT_GE(halvings, 5);
  EXPECT_LE(prev_sum, 65535.0f * 2 / map::kCountScale);
  EXPECT_EQ(map::pfgFromCounts(0, 0), map::kPfgUnknown);
}

TEST_F(Integration, RealKinectFrameMatchesReferenceAndMeasuredSurface) {
  const std::string path = dataPath("redkitchen-0-299") + "/depth/000000.png";
  const cv::Mat raw = cv::imread(path, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(raw.type(), CV_16UC1) << path;
  cv::Mat depth;
  raw.convertTo(depth, CV_32F, 1.0 / 1000.0);
  depth.setTo(kNaN, raw == 0);
  cv::Mat small;
  cv::resize(depth, small, cv::Size(320, 240), 0, 0, cv::INTER_NEAREST);
  const map::MapOptions o = smallOptions();
  map::VoxelPool pool(ctx(), o);
  const map::VolumeSpec spec = map::VolumeSpec::background(o);
  const Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  map::Volume vol(pool, spec, map::backgroundVolumePose(o, spec, T));
  const core::Intrinsics k = testIntrinsics(320, 240);
  Frame f = makeFrame(small, k, T);
  map::VolumeHostData h;
  EXPECT_EQ(fuseAndCompare(vol, f, &h), 0);
  // Measured points lie on the zero level: |psi| at back-projected pixels is small.
  const map::VolumeHostView v = h.view();
  int n = 0, close = 0;
  for (int y = 4; y < k.height; y += 8) {
    for (int x = 4; x < k.width; x += 8) {
      const float d = small.at<float>(y, x);
      if (std::isnan(d)) continue;
      const Eigen::Vector3d pc((x - k.cx) / k.fx * d, (y - k.cy) / k.fy * d, d);
      float psi, w;
      Eigen::Vector3f g;
      if (!map::sampleSdfReference(v, (vol.T_world_volume().inverse() * pc).cast<float>(), &psi, &w,
                                   &g)) {
        continue;
      }
      ++n;
      close += std::abs(psi) < spec.voxel_size_m;
    }
  }
  EXPECT_GT(n, 500);
  EXPECT_GT(close, 0.9 * n) << close << " of " << n;
}

}  // namespace
}  // namespace emf::test
