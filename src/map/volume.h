// A TSDF volume (background or object) drawing its voxel blocks from the VoxelPool.
//
// Frames: the volume frame V has its origin at the corner of the block grid, axes along the
// grid; voxel (i, j, k) has its centre at ((i, j, k) + 0.5) * voxel_size_m in V. The pose
// T_world_volume (host side) maps V to the world.
//
// Device state, allocated when the volume is created (or grown), never per frame:
//   index        int per grid block: pool slot of its TSDF block, -1 = unallocated
//   count_index  (objects) int per grid block: pool slot of its (Fg, Bg) count block
//   needed       uchar per grid block (+ 1 scratch, in whole groups of 16): blocks marked by
//                the current frame
//   block_list   int per grid block: the blocks to integrate this frame
//   state        int[10]: allocation counters and the last report
// Per frame: allocate() (mark + assign + finalize, then one 20-byte read of the report) and
// integrate() (one work-group per listed block). Not thread-safe (one SLAM thread).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <functional>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "cl/context.h"
#include "core/frame.h"
#include "map/map_math.h"
#include "map/map_options.h"
#include "map/voxel_layout.h"
#include "map/voxel_pool.h"

namespace emf::map {

/// Geometry and kind of a volume.
struct VolumeSpec {
  Eigen::Vector3i dims_blocks{64, 64, 64};  // grid extent in blocks per axis
  float voxel_size_m = 0.01f;               // voxel edge, metres
  float truncation_m = 0.1f;                // TSDF truncation, metres (default 10 voxels)
  bool has_counts = false;  // objects: per-voxel (Fg, Bg) in a companion count block
  /// Integrate every allocated block each frame (objects: free-space carving of the whole
  /// volume) instead of only the blocks in the frame's truncation band (background).
  bool integrate_all_blocks = false;
  /// Free space (beyond +truncation) is integrated with weight 1 whatever the association q
  /// (the authors' rule; map.free_space_full_weight for the background).
  bool free_space_full_weight = true;
  /// Observations behind the surface (d < -voxel) count with a weight that falls linearly to 0
  /// at -truncation (Voxblox's drop-off; off in the paper). Objects: objects.behind_dropoff.
  bool behind_dropoff = false;
  /// TSDF weight cap W_max (docs/method.md#integration): map.max_weight for the background,
  /// objects.max_weight for objects.
  float max_weight = 64.0f;
  /// Blocks of the truncation band are integrated on every n-th frame that lists them, in n
  /// phases of a 3-D checkerboard ((x + y + z) mod n of the block); a block that gets its slot
  /// this frame is integrated at once. Each observation then weighs n, so that a voxel averages
  /// and forgets over as many frames as when integrated on every frame. 1 = every frame (the
  /// paper). map.integrate_every for the background; objects integrate every frame.
  int integrate_every = 1;
  /// The truncation band's blocks are found from every n-th pixel in x and y (1 = every pixel).
  /// map.mark_stride for the background; objects mark from every pixel.
  int mark_stride = 1;

  /// The background of docs/method.md#background-volume from map.background_voxel_m /
  /// background_resolution (rounded up to whole blocks) / truncation_voxels.
  static VolumeSpec background(const MapOptions& options);
  /// An object volume of `resolution_voxels` per axis (rounded up to whole blocks).
  static VolumeSpec object(const MapOptions& options, int resolution_voxels, float voxel_size_m);

  Eigen::Vector3f extentM() const {
    return dims_blocks.cast<float>() * (static_cast<float>(kBlockSize) * voxel_size_m);
  }
  int blockCount() const { return dims_blocks.x() * dims_blocks.y() * dims_blocks.z(); }
};

/// The pose of the background volume that puts the first camera at the centre of one face of
/// the volume box, looking in along +z (map.initial_camera_face_offset = 0.5), or that far from
/// the centre along its view axis: T_world_volume.
Eigen::Isometry3d backgroundVolumePose(const MapOptions& options, const VolumeSpec& spec,
                                       const Eigen::Isometry3d& T_world_camera0);

/// One depth frame as the map kernels read it.
struct IntegrationInput {
  const cl::MemHandle* depth = nullptr;    // floats of the intrinsics' size, metres, NaN =
                                           // invalid (e.g. DeviceImage::buffer())
  const cl::MemHandle* weights = nullptr;  // q(u) in [0, 1] per pixel, or nullptr = all ones
  const cl::MemHandle* fg_mask = nullptr;  // objects: p_fg of the matched detection per pixel
                                           // (NaN = occluded, no update), or nullptr
  core::Intrinsics intrinsics;             // of depth (and of weights / fg_mask)
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  /// The pixels that may reach the grid (e.g. the projection of an object's grid box,
  /// track::volumeImageBounds); allocation visits only these. Unset = the whole image.
  std::optional<cv::Rect> pixels;
  /// The part of the grid (volume frame, metres) where blocks may be allocated: blocks that
  /// meet it. Unset = the whole grid. An object's blocks beyond the region its E-step can give
  /// pixels to would never hold its surface (ObjectLifecycle::integrate).
  std::optional<Eigen::AlignedBox3d> region;
};

/// What one allocation did (counts of blocks of this volume).
struct AllocationReport {
  int listed_blocks = 0;     // blocks to integrate this frame
  int allocated_blocks = 0;  // blocks of the volume with a slot, after this allocation
  int dropped_blocks = 0;    // blocks needed this frame that found no slot (pool exhausted)
  int new_blocks = 0;        // blocks that got a slot in this allocation
  int outside_pixels = 0;    // valid pixels whose measured surface lies outside the grid
                             // (of IntegrationInput::pixels when set; those marked from, times
                             // mark_stride^2)
  int phase = 0;             // the checkerboard phase listed (VolumeSpec::integrate_every)
};

/// A host copy of a volume (tests, mesh extraction): its blocks gathered into a compact array.
struct VolumeHostData {
  Eigen::Vector3i dims_blocks{0, 0, 0};
  float voxel_size_m = 0;
  float truncation_m = 0;
  Eigen::Isometry3d T_world_volume = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_volume_initial = Eigen::Isometry3d::Identity();  // see Volume
  std::vector<int32_t> index;        // compact slot per grid block, -1 = unallocated
  std::vector<int32_t> count_index;  // same for count blocks (empty without counts)
  std::vector<Voxel> voxels;         // compact slot s holds [s * kBlockVoxels, +kBlockVoxels)
  std::vector<int32_t> pool_slots;   // pool slot of each compact slot

  VolumeHostView view() const;
  int allocatedBlocks() const;
};

class Volume {
 public:
  /// Creates an empty volume (every block unallocated). Throws InvalidArgument for a grid too
  /// large to index (more than kMaxGridBlocks blocks).
  Volume(VoxelPool& pool, const VolumeSpec& spec, const Eigen::Isometry3d& T_world_volume);
  /// Returns every slot to the pool.
  ~Volume();
  Volume(const Volume&) = delete;
  Volume& operator=(const Volume&) = delete;

  /// Largest grid (blocks) a volume may have: 2^27 blocks = 512^3 blocks (4096^3 voxels).
  static constexpr int kMaxGridBlocks = 1 << 27;

  const VolumeSpec& spec() const { return spec_; }
  /// Names this volume for its lifetime, unique in the process (> 0): unlike index(), which
  /// grow() replaces, it survives growth. State kept per volume across frames is keyed by it.
  uint64_t key() const { return key_; }
  const Eigen::Isometry3d& T_world_volume() const { return T_world_volume_; }
  void setPose(const Eigen::Isometry3d& T_world_volume) { T_world_volume_ = T_world_volume; }
  /// The volume frame at creation, in the current volume frame: grow() moves the grid origin
  /// but not this frame, which stays fixed to the content (a translation by whole blocks).
  /// Object poses and trajectories are reported in it, so that they do not jump on growth.
  const Eigen::Isometry3d& T_volume_initial() const { return T_volume_initial_; }
  Eigen::Isometry3d T_world_initial() const { return T_world_volume_ * T_volume_initial_; }

  /// Marks the blocks within +-truncation of the frame's depth and gives them slots (on the
  /// device); fills the block list integrate() uses. Exhaustion: see VoxelPool.
  AllocationReport allocate(const IntegrationInput& frame);
  /// Integrates the frame into the blocks listed by the last allocate() (same frame).
  void integrate(const IntegrationInput& frame);
  /// allocate() then integrate().
  AllocationReport fuse(const IntegrationInput& frame);

  /// Extends the grid by whole blocks on each side, keeping voxel size and every allocated
  /// block (re-indexed, not copied). The volume origin moves by -add_low blocks, so the world
  /// position of every voxel is unchanged. Allocates the new (larger) index buffers.
  void grow(const Eigen::Vector3i& add_low_blocks, const Eigen::Vector3i& add_high_blocks);
  /// Moves the grid by whole blocks (volume frame axes), keeping its dims: the volume origin
  /// moves by +blocks, so every voxel that stays keeps its world position (re-indexed, not
  /// copied) and the blocks that leave the grid (block coordinates b with b - blocks outside
  /// the grid) return their slots to the pool, zeroed. Mesh what leaves before (see
  /// map/volume_follow.h). Only for volumes without counts (the background). Returns the
  /// blocks released.
  int shift(const Eigen::Vector3i& blocks);
  /// Returns every slot to the pool (the volume stays usable, empty).
  void clear();

  /// Blocks with a slot (from the last allocation or clear/grow).
  int allocatedBlocks() const { return last_report_.allocated_blocks; }
  const AllocationReport& lastReport() const { return last_report_; }
  /// Device bytes of this volume's own buffers (index grids, marks, list, state).
  size_t indexBytes() const;

  /// Which blocks (grid coordinates) a partial download reads; the others read as unallocated.
  using BlockFilter = std::function<bool(const Eigen::Vector3i& block)>;
  /// Copies the allocated blocks (those `keep` accepts, when given) to the host (allocates; not
  /// for the per-frame path).
  VolumeHostData download(const BlockFilter& keep = {}) const;

  // Device state for other kernels (tracking, E-step, ray casting).
  const cl::MemHandle& index() const { return index_; }
  const cl::MemHandle& countIndex() const {
    return has_counts_buffer_ ? count_index_ : pool_.dummy();
  }
  cl_int4 dimsBlocks() const;
  VoxelPool& pool() const { return pool_; }

 private:
  void createBuffers();
  void checkFrame(const IntegrationInput& frame, const char* what) const;

  VoxelPool& pool_;
  cl::Context& ctx_;
  VolumeSpec spec_;
  uint64_t key_;
  Eigen::Isometry3d T_world_volume_;
  Eigen::Isometry3d T_volume_initial_ = Eigen::Isometry3d::Identity();
  bool has_counts_buffer_ = false;
  cl::MemHandle index_, count_index_, needed_, block_list_, state_;
  cl::KernelHandle mark_, assign_, finalize_, integrate_, count_, release_, reindex_, evict_;
  AllocationReport last_report_;
  int32_t report_[5] = {0, 0, 0, 0, 0};
  int64_t allocations_ = 0;  // allocate() calls: the integration phase (integrate_every)
};

}  // namespace emf::map
