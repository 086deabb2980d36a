// The fixed pool: sizing from the budget, exhaustion (allocate what fits, count the rest, no
// corruption), slots returned by clear/delete and clean when reused, growing volumes.
#include <random>
#include <set>

#include "common/error.h"
#include "map_fixture.h"

namespace emf::test {
namespace {

map::MapOptions options2cm() {
  map::MapOptions o;
  o.memory_mb = 8;
  o.background_voxel_m = 0.02;
  o.background_resolution = 256;
  o.mark_stride = 1;  // the tests compare with the reference's blocks of every pixel
  return o;
}

class Pool : public MapTest {};

TEST_F(Pool, SizedFromTheBudgetInOneAllocation) {
  map::MapOptions o;
  o.memory_mb = 8;
  map::VoxelPool pool(ctx(), o);
  EXPECT_EQ(pool.capacitySlots(), 8 * 1024 * 1024 / 2048);
  const map::PoolStats s = pool.stats();
  EXPECT_EQ(s.pool_bytes, size_t{8} << 20);
  EXPECT_EQ(s.free_slots, 4096);
  EXPECT_EQ(s.used_slots, 0);
  EXPECT_EQ(s.dropped_blocks, 0);
  size_t bytes = 0;
  clGetMemObjectInfo(pool.voxels().get(), CL_MEM_SIZE, sizeof(bytes), &bytes, nullptr);
  EXPECT_EQ(bytes, size_t{8} << 20);
}

TEST_F(Pool, BudgetBeyondTheIndexRangeIsAConfigError) {
  map::MapOptions o;
  o.memory_mb = 65536;
  try {
    map::VoxelPool pool(ctx(), o);
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("map.memory_mb"), std::string::npos) << e.what();
  }
}

TEST_F(Pool, ExhaustionAllocatesWhatFitsCountsTheRestAndCorruptsNothing) {
  const map::MapOptions o = options2cm();
  constexpr int kCapacity = 150;
  map::VoxelPool pool(ctx(), o, kCapacity);
  const map::VolumeSpec spec = map::VolumeSpec::background(o);
  const Eigen::Isometry3d T0 = Eigen::Isometry3d::Identity();
  map::Volume vol(pool, spec, map::backgroundVolumePose(o, spec, T0));
  const core::Intrinsics k = testIntrinsics(160, 120);
  const Scene scene;
  const Eigen::Isometry3d poses[] = {
      T0, lookAt(Eigen::Vector3d(0.5, -0.2, 0.3), Eigen::Vector3d(-0.2, 0.5, 2.5)),
      lookAt(Eigen::Vector3d(-0.4, 0.0, 0.1), Eigen::Vector3d(0.5, 0.3, 2.0))};
  int64_t dropped_total = 0;
  std::set<int> kept;  // blocks allocated so far: never lose their slot
  for (const auto& T : poses) {
    Frame f = makeFrame(renderDepth(scene, k, T), k, T);
    const map::VolumeHostData before = vol.download();
    const map::PoseRows T_vc = map::PoseRows::from(vol.T_world_volume().inverse() * T);
    const std::vector<uint8_t> marked = map::markBlocksReference(
        f.depth_host, cameraF(k), T_vc, 8 * spec.voxel_size_m, spec.truncation_m, spec.dims_blocks);
    int needed_new = 0;
    for (size_t i = 0; i < marked.size(); ++i) needed_new += marked[i] && before.index[i] < 0;
    const int free_before = pool.stats().free_slots;
    // Device result vs reference integration on the blocks that did get a slot: exact.
    map::VolumeHostData after;
    EXPECT_EQ(fuseAndCompare(vol, f, &after, /*check_alloc=*/false), 0);
    const map::AllocationReport& rep = vol.lastReport();
    const int granted = std::min(needed_new, free_before);
    EXPECT_EQ(rep.new_blocks, granted);
    EXPECT_EQ(rep.dropped_blocks, needed_new - granted);
    dropped_total += needed_new - granted;
    // Every newly allocated block was marked; every earlier block kept its slot.
    for (size_t i = 0; i < marked.size(); ++i) {
      if (after.index[i] >= 0 && before.index[i] < 0) {
        EXPECT_TRUE(marked[i]) << "block " << i;
      }
      if (before.index[i] >= 0) {
        EXPECT_EQ(after.pool_slots[static_cast<size_t>(after.index[i])],
                  before.pool_slots[static_cast<size_t>(before.index[i])]);
      }
    }
    for (size_t i = 0; i < after.index.size(); ++i) {
      if (after.index[i] >= 0) kept.insert(static_cast<int>(i));
    }
  }
  const map::PoolStats s = pool.stats();
  EXPECT_EQ(s.free_slots, 0);
  EXPECT_EQ(s.used_slots, kCapacity);
  EXPECT_EQ(vol.allocatedBlocks(), kCapacity);
  EXPECT_EQ(static_cast<int>(kept.size()), kCapacity);
  EXPECT_GT(dropped_total, 100);
  EXPECT_EQ(s.dropped_blocks, dropped_total);
  EXPECT_DOUBLE_EQ(s.occupancy(), 1.0);

  // Deleting the volume returns every slot; a new volume gets clean (zero) slots.
  vol.clear();
  EXPECT_EQ(pool.stats().free_slots, kCapacity);
  EXPECT_EQ(vol.allocatedBlocks(), 0);
  map::Volume fresh(pool, spec, map::backgroundVolumePose(o, spec, T0));
  Frame f = makeFrame(renderDepth(scene, k, poses[1]), k, poses[1]);
  fresh.allocate(f.input);
  const map::VolumeHostData h = fresh.download();
  EXPECT_EQ(h.allocatedBlocks(), kCapacity);
  for (const map::Voxel& v : h.voxels) {
    ASSERT_EQ(v.tsdf_q, 0);
    ASSERT_EQ(v.weight_q, 0);
  }
}

TEST_F(Pool, ObjectBlocksTakeTwoSlotsAndAnOddLastSlotIsNotSplit) {
  const map::MapOptions o = options2cm();
  constexpr int kCapacity = 41;  // odd: 20 object blocks fit, one slot stays free
  map::VoxelPool pool(ctx(), o, kCapacity);
  const Scene scene;
  map::VolumeSpec spec = map::VolumeSpec::object(o, 48, 0.02f);
  Eigen::Isometry3d T_wv = Eigen::Isometry3d::Identity();
  T_wv.translation() = scene.spheres[1].centre_w - Eigen::Vector3d::Constant(0.48);
  map::Volume vol(pool, spec, T_wv);
  const core::Intrinsics k = testIntrinsics(160, 120);
  Frame f = makeFrame(renderDepth(scene, k, Eigen::Isometry3d::Identity()), k,
                      Eigen::Isometry3d::Identity());
  const map::AllocationReport rep = vol.allocate(f.input);
  const map::VolumeHostData h = vol.download();
  EXPECT_EQ(rep.new_blocks, 20);
  EXPECT_GT(rep.dropped_blocks, 0);
  EXPECT_EQ(pool.stats().free_slots, 1);
  std::set<int32_t> slots;
  for (size_t i = 0; i < h.index.size(); ++i) {
    EXPECT_EQ(h.index[i] >= 0, h.count_index[i] >= 0) << "block " << i;
    if (h.index[i] >= 0) {
      slots.insert(h.pool_slots[static_cast<size_t>(h.index[i])]);
      slots.insert(h.pool_slots[static_cast<size_t>(h.count_index[i])]);
    }
  }
  EXPECT_EQ(slots.size(), 40u);  // all distinct
  vol.clear();
  EXPECT_EQ(pool.stats().free_slots, kCapacity);
}

TEST_F(Pool, DestroyingAVolumeReturnsItsSlots) {
  const map::MapOptions o = options2cm();
  map::VoxelPool pool(ctx(), o);
  const Scene scene;
  const core::Intrinsics k = testIntrinsics(160, 120);
  const Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  Frame f = makeFrame(renderDepth(scene, k, T), k, T);
  const map::VolumeSpec spec = map::VolumeSpec::background(o);
  int used = 0;
  {
    map::Volume a(pool, spec, map::backgroundVolumePose(o, spec, T));
    map::Volume b(pool, map::VolumeSpec::object(o, 64, 0.01f), Eigen::Isometry3d::Identity());
    used = a.fuse(f.input).allocated_blocks;
    used += 2 * b.fuse(f.input).allocated_blocks;
    EXPECT_EQ(pool.stats().used_slots, used);
    EXPECT_GT(used, 100);
  }
  EXPECT_EQ(pool.stats().used_slots, 0);
}

TEST_F(Pool, BadFramesAreRejectedWithAMessage) {
  const map::MapOptions o = options2cm();
  map::VoxelPool pool(ctx(), o);
  const map::VolumeSpec spec = map::VolumeSpec::background(o);
  map::Volume vol(pool, spec, Eigen::Isometry3d::Identity());
  const core::Intrinsics small = testIntrinsics(160, 120);
  Frame f = makeFrame(cv::Mat(small.height, small.width, CV_32FC1, cv::Scalar(1.0f)), small,
                      Eigen::Isometry3d::Identity());
  map::IntegrationInput in = f.input;
  in.intrinsics = testIntrinsics(320, 240);  // larger than the uploaded image
  try {
    vol.allocate(in);
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("320x240"), std::string::npos) << e.what();
  }
  in = f.input;
  in.depth = nullptr;
  EXPECT_THROW(vol.integrate(in), InvalidArgument);
  map::DeviceImage image(ctx(), 160, 120);
  EXPECT_THROW(image.upload(cv::Mat(240, 320, CV_32FC1)), InvalidArgument);
  EXPECT_THROW(image.upload(cv::Mat(120, 160, CV_16UC1)), InvalidArgument);
  EXPECT_EQ(pool.stats().used_slots, 0);  // nothing happened
  // Grids too large to index are refused when the volume is created.
  map::VolumeSpec huge = spec;
  huge.dims_blocks = Eigen::Vector3i(1024, 1024, 1024);
  EXPECT_THROW(map::Volume(pool, huge, Eigen::Isometry3d::Identity()), InvalidArgument);
}

TEST_F(Pool, GrowReindexesWithoutMovingVoxels) {
  const map::MapOptions o = options2cm();
  map::VoxelPool pool(ctx(), o);
  const Scene scene;
  const Sphere& s = scene.spheres[0];
  map::VolumeSpec spec = map::VolumeSpec::object(o, 32, 0.02f);  // 0.64 m: cuts the sphere
  Eigen::Isometry3d T_wv = Eigen::Isometry3d::Identity();
  T_wv.translation() = s.centre_w - Eigen::Vector3d(0.2, 0.2, 0.5);
  map::Volume vol(pool, spec, T_wv);
  const core::Intrinsics k = testIntrinsics(160, 120);
  const Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  Frame f = makeFrame(renderDepth(scene, k, T), k, T);
  vol.fuse(f.input);
  const map::VolumeHostData h0 = vol.download();
  const int used0 = pool.stats().used_slots;
  const uint64_t key0 = vol.key();
  const cl_mem index0 = vol.index().get();

  const Eigen::Vector3i low(1, 2, 0), high(0, 1, 3);
  vol.grow(low, high);
  // A new index buffer, the same key (what per-volume state across frames is keyed by).
  EXPECT_NE(vol.index().get(), index0);
  EXPECT_EQ(vol.key(), key0);
  EXPECT_NE(map::Volume(pool, spec, T_wv).key(), key0);
  EXPECT_EQ(vol.spec().dims_blocks, Eigen::Vector3i(5, 7, 7));
  EXPECT_EQ(pool.stats().used_slots, used0);  // no voxel copied, no slot taken
  const map::VolumeHostData h1 = vol.download();
  // World position of the origin moved by -low blocks.
  const Eigen::Vector3d shift = vol.T_world_volume().translation() - T_wv.translation();
  EXPECT_LT((shift + low.cast<double>() * 0.16).norm(), 1e-6) << shift.transpose();
  // The initial frame (where object poses are reported) stays where it was.
  EXPECT_TRUE(vol.T_world_initial().isApprox(T_wv, 1e-9));
  EXPECT_LT((vol.T_volume_initial().translation() - low.cast<double>() * 0.16).norm(), 1e-6);
  EXPECT_TRUE(h1.T_volume_initial.isApprox(vol.T_volume_initial()));
  // Every old block is at old + low, pointing to the same pool slot.
  for (int lin = 0; lin < spec.blockCount(); ++lin) {
    const Eigen::Vector3i b = map::blockCoords(spec.dims_blocks, lin);
    const int nl = map::blockLinear(h1.dims_blocks, b + low);
    const int s0 = h0.index[static_cast<size_t>(lin)];
    const int s1 = h1.index[static_cast<size_t>(nl)];
    ASSERT_EQ(s0 >= 0, s1 >= 0);
    if (s0 >= 0) {
      EXPECT_EQ(h0.pool_slots[static_cast<size_t>(s0)], h1.pool_slots[static_cast<size_t>(s1)]);
      EXPECT_EQ(h0.pool_slots[static_cast<size_t>(h0.count_index[static_cast<size_t>(lin)])],
                h1.pool_slots[static_cast<size_t>(h1.count_index[static_cast<size_t>(nl)])]);
    }
  }
  EXPECT_EQ(h1.allocatedBlocks(), h0.allocatedBlocks());
  // The SDF at fixed world points is unchanged.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.05f, 0.59f);
  int compared = 0;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3f p0 = drawXyz<Eigen::Vector3f>([&] { return u(rng); });
    const Eigen::Vector3d p_w = T_wv * p0.cast<double>();
    const Eigen::Vector3f p1 = (vol.T_world_volume().inverse() * p_w).cast<float>();
    float a, wa, b, wb;
    Eigen::Vector3f ga, gb;
    const bool oka = map::sampleSdfReference(h0.view(), p0, &a, &wa, &ga);
    const bool okb = map::sampleSdfReference(h1.view(), p1, &b, &wb, &gb);
    ASSERT_EQ(oka, okb) << i;
    if (!oka) continue;
    ++compared;
    EXPECT_NEAR(a, b, 1e-6f);
    EXPECT_NEAR(wa, wb, 1e-5f);
  }
  EXPECT_GT(compared, 200);
  // Integration keeps working in the grown grid and reaches the new blocks.
  Frame f2 = makeFrame(renderDepth(scene, k, T), k, T);
  EXPECT_EQ(fuseAndCompare(vol, f2), 0);
  EXPECT_GT(vol.allocatedBlocks(), h0.allocatedBlocks());
}

}  // namespace
}  // namespace emf::test
