#include "map/volume_follow.h"

#include <algorithm>
#include <cmath>

#include "map/volume_host_access.h"

namespace emf::map {

FollowRule followRule(const MapOptions& options, const VolumeSpec& spec) {
  FollowRule rule;
  rule.focus_m = options.initial_camera_face_offset * static_cast<double>(spec.extentM().z());
  rule.trigger_m = options.follow_trigger_m;
  return rule;
}

Eigen::Vector3i followShift(const VolumeSpec& spec, const Eigen::Isometry3d& T_world_volume,
                            const Eigen::Isometry3d& T_world_camera, const FollowRule& rule) {
  const Eigen::Vector3d focus_v =
      T_world_volume.inverse() * (T_world_camera * Eigen::Vector3d(0.0, 0.0, rule.focus_m));
  const Eigen::Vector3d off = focus_v - 0.5 * spec.extentM().cast<double>();
  const double block_m = static_cast<double>(kBlockSize) * static_cast<double>(spec.voxel_size_m);
  // A trigger below one block would move the grid back and forth by a block on every frame.
  const double trigger = std::max(rule.trigger_m, block_m);
  Eigen::Vector3i blocks = Eigen::Vector3i::Zero();
  for (int a = 0; a < 3; ++a) {
    const double excess = std::fabs(off[a]) - trigger;
    if (!(excess > 0.0)) continue;  // within the trigger (or NaN: no move)
    const int n = std::min(kMaxFollowStepBlocks, static_cast<int>(std::ceil(excess / block_m)));
    blocks[a] = off[a] > 0.0 ? n : -n;
  }
  return blocks;
}

Volume::BlockFilter leavingMeshBlocks(const Eigen::Vector3i& blocks, const Eigen::Vector3i& dims) {
  // Staying blocks are [blocks, blocks + dims); cubes with a corner outside lie in blocks
  // below blocks + 1 or from blocks + dims - 1 on, along some axis (and read those up to +1).
  const Eigen::Vector3i low = blocks, high = blocks + dims - Eigen::Vector3i::Ones();
  return [low, high](const Eigen::Vector3i& b) {
    return (b.array() <= low.array()).any() || (b.array() >= high.array()).any();
  };
}

void extractLeavingMesh(const Volume& volume, const Eigen::Vector3i& blocks, MeshSink& sink,
                        bool force_download) {
  const Eigen::Vector3i dims = volume.spec().dims_blocks;
  const Volume::BlockFilter keep = leavingMeshBlocks(blocks, dims);
  const VolumeHostAccess access =
      force_download ? VolumeHostAccess::downloaded(volume, keep) : VolumeHostAccess(volume, keep);
  extractLeavingMesh(access.view(), access.T_world_volume(), blocks, sink);
}

void extractLeavingMesh(const VolumeHostView& view, const Eigen::Isometry3d& T_world_volume,
                        const Eigen::Vector3i& blocks, MeshSink& sink) {
  MeshOptions options;
  // The voxels that stay: blocks b with b - blocks inside the grid.
  options.leaving =
      MeshOptions::VoxelBox{blocks * kBlockSize, (blocks + view.dims_blocks) * kBlockSize};
  extractMesh(view, T_world_volume, options, sink);
}

}  // namespace emf::map
