// Shared fixture of the map tests on the OpenCL device: a pool, device images and helpers that
// compare device volumes with the CPU references.
#pragma once

#include <memory>
#include <vector>

#include "map/device_image.h"
#include "map/map_reference.h"
#include "map/volume.h"
#include "map/voxel_pool.h"
#include "map_test_scene.h"
#include "test_support.h"

namespace emf::test {

/// Quantised voxel differences allowed between kernel and CPU reference (int16 steps). The
/// kernels and references do the same float operations in the same order (FP_CONTRACT OFF), so
/// they agree exactly except where a division rounds differently; one step of 1/32767 of the
/// truncation is far below anything that matters.
constexpr int kTsdfToleranceSteps = 1;
constexpr int kWeightToleranceSteps = 1;

/// A 32 MiB pool and a 5.12 m background at 2 cm (256 voxels): the map tests' usual setting.
inline map::MapOptions smallOptions() {
  map::MapOptions o;
  o.memory_mb = 32;
  o.background_voxel_m = 0.02;
  o.background_resolution = 256;
  // The paper's integration (every block of the band, found from every pixel): the tests compare
  // block for block; those of map.integrate_every and map.mark_stride set them.
  o.integrate_every = 1;
  o.mark_stride = 1;
  return o;
}

class MapTest : public WithClQueue {
 protected:
  /// A device frame: depth (and optional q / mask) uploaded, intrinsics and pose set.
  struct Frame {
    std::unique_ptr<map::DeviceImage> depth, weights, mask;
    cv::Mat depth_host, weights_host, mask_host;
    map::IntegrationInput input;
  };

  Frame makeFrame(const cv::Mat& depth, const core::Intrinsics& k, const Eigen::Isometry3d& T_wc,
                  const cv::Mat& weights = cv::Mat(), const cv::Mat& mask = cv::Mat()) {
    Frame f;
    f.depth = std::make_unique<map::DeviceImage>(ctx(), k.width, k.height);
    f.depth->upload(depth, "test depth");
    f.depth_host = depth;
    f.input.depth = &f.depth->buffer();
    f.input.intrinsics = k;
    f.input.T_world_camera = T_wc;
    if (!weights.empty()) {
      f.weights = std::make_unique<map::DeviceImage>(ctx(), k.width, k.height);
      f.weights->upload(weights, "test weights");
      f.weights_host = weights;
      f.input.weights = &f.weights->buffer();
    }
    if (!mask.empty()) {
      f.mask = std::make_unique<map::DeviceImage>(ctx(), k.width, k.height);
      f.mask->upload(mask, "test mask");
      f.mask_host = mask;
      f.input.fg_mask = &f.mask->buffer();
    }
    return f;
  }

  /// Fuses three views of `scene` (the first camera and two others looking into the room) into
  /// `volume` at the size of `k`.
  void fuseThreeViews(map::Volume& volume, const Scene& scene, const core::Intrinsics& k) {
    const Eigen::Isometry3d T0 = Eigen::Isometry3d::Identity();
    for (const Eigen::Isometry3d& T :
         {T0, lookAt(Eigen::Vector3d(0.4, -0.1, 0.2), Eigen::Vector3d(0.0, 0.3, 2.0)),
          lookAt(Eigen::Vector3d(-0.3, 0.1, 0.5), Eigen::Vector3d(0.3, 0.2, 1.6))}) {
      Frame f = makeFrame(renderDepth(scene, k, T), k, T);
      volume.fuse(f.input);
    }
  }

  /// Runs allocate() + integrate() on the device and the CPU reference on the host copy taken
  /// after allocation; returns the number of voxels beyond tolerance (and the device copy).
  int fuseAndCompare(map::Volume& vol, const Frame& f, map::VolumeHostData* out = nullptr,
                     bool check_alloc = true) {
    const map::VolumeHostData before = vol.download();
    const map::AllocationReport rep = vol.allocate(f.input);
    map::VolumeHostData ref = vol.download();
    const map::VolumeSpec& s = vol.spec();
    const map::PoseRows T_vc =
        map::PoseRows::from(vol.T_world_volume().inverse() * f.input.T_world_camera);
    const std::vector<uint8_t> marked =
        map::markBlocksReference(f.depth_host, cameraF(f.input.intrinsics), T_vc,
                                 static_cast<float>(map::kBlockSize) * s.voxel_size_m,
                                 s.truncation_m, s.dims_blocks, s.mark_stride);
    if (check_alloc && rep.dropped_blocks == 0) {
      // Allocated after = allocated before  U  marked.
      for (size_t i = 0; i < marked.size(); ++i) {
        const bool expect = before.index[i] >= 0 || marked[i];
        EXPECT_EQ(ref.index[i] >= 0, expect) << "block " << i;
      }
    }
    const std::vector<int> list = map::blockListReference(
        ref, marked, s.integrate_all_blocks, s.integrate_every, rep.phase, &before.index);
    EXPECT_EQ(static_cast<int>(list.size()), rep.listed_blocks);
    vol.integrate(f.input);
    const map::VolumeHostData dev = vol.download();
    const map::PoseRows T_cv =
        map::PoseRows::from(f.input.T_world_camera.inverse() * vol.T_world_volume());
    map::integrateReference(ref, list, f.depth_host, f.weights_host, f.mask_host,
                            cameraF(f.input.intrinsics), T_cv, vol.spec().max_weight,
                            vol.spec().free_space_full_weight, vol.spec().behind_dropoff,
                            static_cast<float>(std::max(1, s.integrate_every)));
    EXPECT_EQ(dev.index, ref.index);
    EXPECT_EQ(dev.count_index, ref.count_index);
    std::vector<bool> count_slot(dev.voxels.size() / map::kBlockVoxels, false);
    for (int32_t c : dev.count_index) {
      if (c >= 0) count_slot[static_cast<size_t>(c)] = true;
    }
    int bad = 0;
    const size_t n = std::min(dev.voxels.size(), ref.voxels.size());
    EXPECT_EQ(dev.voxels.size(), ref.voxels.size());
    for (size_t i = 0; i < n; ++i) {
      const bool is_count = count_slot[i / map::kBlockVoxels];
      const int dt = std::abs(dev.voxels[i].tsdf_q - ref.voxels[i].tsdf_q);
      const int dw = std::abs(dev.voxels[i].weight_q - ref.voxels[i].weight_q);
      const bool ok = is_count ? (dt == 0 && dw == 0)
                               : (dt <= kTsdfToleranceSteps && dw <= kWeightToleranceSteps);
      if (!ok && bad++ < 5) {
        ADD_FAILURE() << "voxel " << i << (is_count ? " (counts)" : "") << ": device ("
                      << dev.voxels[i].tsdf_q << ", " << dev.voxels[i].weight_q
                      << ") vs reference (" << ref.voxels[i].tsdf_q << ", "
                      << ref.voxels[i].weight_q << ")";
      }
    }
    if (out) *out = dev;
    return bad;
  }
};

}  // namespace emf::test
