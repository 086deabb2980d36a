#include "map/volume.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <string>

#include "cl/cl_error.h"
#include "common/error.h"

namespace emf::map {

namespace {

constexpr int kCountGroup = 512;      // work items per block in count_blocks (one per voxel)
constexpr int kVolumeStateInts = 10;  // layout in kernels_cl/map_alloc.cl (EMF_VOL_*)
constexpr int kVolumeReport = 4;
constexpr size_t kAssignGroup = 16;  // EMF_ASSIGN_GROUP in kernels_cl/map_alloc.cl

/// Bytes of the needed flags of n blocks: one per block and the scratch flag, in whole groups.
size_t neededBytes(size_t n) { return (n + 1 + kAssignGroup - 1) / kAssignGroup * kAssignGroup; }

int blocksFor(int voxels) { return (voxels + kBlockSize - 1) / kBlockSize; }

cl_float4 row4(const PoseRows& p, int i) {
  return cl_float4{{p.r[i][0], p.r[i][1], p.r[i][2], p.r[i][3]}};
}

std::string dimsText(const Eigen::Vector3i& d) {
  return std::to_string(d.x()) + "x" + std::to_string(d.y()) + "x" + std::to_string(d.z());
}

}  // namespace

VolumeSpec VolumeSpec::background(const MapOptions& options) {
  VolumeSpec s;
  const int b = blocksFor(options.background_resolution);
  s.dims_blocks = Eigen::Vector3i(b, b, b);
  s.voxel_size_m = static_cast<float>(options.background_voxel_m);
  s.truncation_m = static_cast<float>(options.truncation_voxels * options.background_voxel_m);
  s.free_space_full_weight = options.free_space_full_weight;
  s.max_weight = static_cast<float>(options.max_weight);
  s.integrate_every = options.integrate_every;
  s.mark_stride = options.mark_stride;
  return s;
}

VolumeSpec VolumeSpec::object(const MapOptions& options, int resolution_voxels,
                              float voxel_size_m) {
  VolumeSpec s;
  const int b = blocksFor(resolution_voxels);
  s.dims_blocks = Eigen::Vector3i(b, b, b);
  s.voxel_size_m = voxel_size_m;
  s.truncation_m = static_cast<float>(options.truncation_voxels) * voxel_size_m;
  s.has_counts = true;
  s.integrate_all_blocks = true;
  s.free_space_full_weight = options.free_space_full_weight;
  s.max_weight = static_cast<float>(options.max_weight);
  return s;
}

Eigen::Isometry3d backgroundVolumePose(const MapOptions& options, const VolumeSpec& spec,
                                       const Eigen::Isometry3d& T_world_camera0) {
  const Eigen::Vector3d ext = spec.extentM().cast<double>();
  // Camera at (ext.x/2, ext.y/2, ext.z * (0.5 - offset)) in the volume frame, axes aligned.
  Eigen::Isometry3d T_camera_volume = Eigen::Isometry3d::Identity();
  T_camera_volume.translation() = -Eigen::Vector3d(
      0.5 * ext.x(), 0.5 * ext.y(), ext.z() * (0.5 - options.initial_camera_face_offset));
  return T_world_camera0 * T_camera_volume;
}

VolumeHostView VolumeHostData::view() const {
  VolumeHostView v;
  v.index = index.data();
  v.dims_blocks = dims_blocks;
  v.voxels = voxels.data();
  v.voxel_size_m = voxel_size_m;
  v.truncation_m = truncation_m;
  v.count_index = count_index.empty() ? nullptr : count_index.data();
  return v;
}

int VolumeHostData::allocatedBlocks() const {
  return static_cast<int>(std::count_if(index.begin(), index.end(), [](int s) { return s >= 0; }));
}

namespace {
uint64_t nextKey() {
  static std::atomic<uint64_t> last{0};
  return ++last;
}
}  // namespace

Volume::Volume(VoxelPool& pool, const VolumeSpec& spec, const Eigen::Isometry3d& T_world_volume)
    : pool_(pool),
      ctx_(pool.context()),
      spec_(spec),
      key_(nextKey()),
      T_world_volume_(T_world_volume) {
  if ((spec.dims_blocks.array() < 1).any() ||
      static_cast<int64_t>(spec.dims_blocks.x()) * spec.dims_blocks.y() * spec.dims_blocks.z() >
          kMaxGridBlocks) {
    throw InvalidArgument("volume grid of " + dimsText(spec.dims_blocks) +
                          " blocks is empty or larger than " + std::to_string(kMaxGridBlocks) +
                          " blocks (check map.background_resolution / objects.resolution)");
  }
  if (!(spec.voxel_size_m > 0.f) || !(spec.truncation_m > 0.f)) {
    throw InvalidArgument(
        "volume voxel size and truncation must be positive (map.*_voxel_m, "
        "map.truncation_voxels)");
  }
  has_counts_buffer_ = spec.has_counts;
  mark_ = ctx_.kernel("map_alloc", "mark_blocks");
  assign_ = ctx_.kernel("map_alloc", "assign_blocks");
  finalize_ = ctx_.kernel("map_alloc", "finalize_allocation");
  release_ = ctx_.kernel("map_alloc", "release_blocks");
  reindex_ = ctx_.kernel("map_alloc", "reindex_blocks");
  evict_ = ctx_.kernel("map_alloc", "evict_blocks");
  integrate_ = ctx_.kernel("tsdf_integrate", "integrate_blocks");
  if (spec.has_counts) count_ = ctx_.kernel("tsdf_integrate", "count_blocks");
  createBuffers();
  const int32_t state[kVolumeStateInts] = {};
  state_ = ctx_.buffer(CL_MEM_READ_WRITE, sizeof(state), state);
}

Volume::~Volume() {
  try {
    clear();
  } catch (const std::exception&) {
    // The device is gone; the pool goes with it. Nothing useful to do in a destructor.
  }
}

void Volume::createBuffers() {
  const size_t n = static_cast<size_t>(spec_.blockCount());
  const cl_int minus_one = -1;
  const cl_uchar zero = 0;
  index_ = ctx_.buffer(CL_MEM_READ_WRITE, n * sizeof(int32_t));
  EMF_CL_CHECK(clEnqueueFillBuffer(ctx_.queue(), index_.get(), &minus_one, sizeof(minus_one), 0,
                                   n * sizeof(int32_t), 0, nullptr, nullptr));
  if (spec_.has_counts) {
    count_index_ = ctx_.buffer(CL_MEM_READ_WRITE, n * sizeof(int32_t));
    EMF_CL_CHECK(clEnqueueFillBuffer(ctx_.queue(), count_index_.get(), &minus_one,
                                     sizeof(minus_one), 0, n * sizeof(int32_t), 0, nullptr,
                                     nullptr));
  }
  // One flag per block, and one more that mark_blocks writes for the lanes it does not mark;
  // whole groups of kAssignGroup flags (assign_blocks reads a group at once).
  const size_t flag_bytes = neededBytes(n);
  needed_ = ctx_.buffer(CL_MEM_READ_WRITE, flag_bytes);
  EMF_CL_CHECK(clEnqueueFillBuffer(ctx_.queue(), needed_.get(), &zero, sizeof(zero), 0, flag_bytes,
                                   0, nullptr, nullptr));
  block_list_ = ctx_.buffer(CL_MEM_READ_WRITE, n * sizeof(int32_t));
  ctx_.finish();
}

size_t Volume::indexBytes() const {
  const size_t n = static_cast<size_t>(spec_.blockCount());
  return n * sizeof(int32_t) * (spec_.has_counts ? 3 : 2) + neededBytes(n) + kVolumeStateInts * 4;
}

cl_int4 Volume::dimsBlocks() const {
  return cl_int4{{spec_.dims_blocks.x(), spec_.dims_blocks.y(), spec_.dims_blocks.z(), 0}};
}

void Volume::checkFrame(const IntegrationInput& frame, const char* what) const {
  if (!frame.depth || !frame.depth->get()) {
    throw InvalidArgument(std::string(what) + ": no depth image");
  }
  const core::Intrinsics& k = frame.intrinsics;
  if (!k.valid()) {
    throw InvalidArgument(std::string(what) + ": invalid intrinsics " + std::to_string(k.width) +
                          "x" + std::to_string(k.height));
  }
  // The kernels read width x height floats from each image: check the buffers hold them.
  const size_t need = static_cast<size_t>(k.width) * static_cast<size_t>(k.height) * sizeof(float);
  for (const cl::MemHandle* m : {frame.depth, frame.weights, frame.fg_mask}) {
    if (!m) continue;
    size_t bytes = 0;
    EMF_CL_CHECK(clGetMemObjectInfo(m->get(), CL_MEM_SIZE, sizeof(bytes), &bytes, nullptr));
    if (bytes < need) {
      throw InvalidArgument(std::string(what) + ": an image buffer of " + std::to_string(bytes) +
                            " bytes is smaller than " + std::to_string(k.width) + "x" +
                            std::to_string(k.height) + " floats");
    }
  }
}

AllocationReport Volume::allocate(const IntegrationInput& frame) {
  checkFrame(frame, "Volume::allocate");
  const PoseRows T_volume_camera = PoseRows::from(T_world_volume_.inverse() * frame.T_world_camera);
  const core::Intrinsics& k = frame.intrinsics;
  const cl_int4 dims = dimsBlocks();
  const cv::Rect image(0, 0, k.width, k.height);
  const cv::Rect rect = frame.pixels ? *frame.pixels & image : image;
  const cl_int4 rect_arg = {{rect.x, rect.y, rect.width, rect.height}};
  const double block_m = static_cast<double>(kBlockSize) * spec_.voxel_size_m;
  cl_int4 mark_lo = {{0, 0, 0, 0}}, mark_hi = dims;
  if (frame.region) {
    for (int a = 0; a < 3; ++a) {
      const double lo = std::floor(frame.region->min()[a] / block_m);
      const double hi = std::floor(frame.region->max()[a] / block_m) + 1.0;
      mark_lo.s[a] = static_cast<cl_int>(std::clamp(lo, 0.0, static_cast<double>(dims.s[a])));
      mark_hi.s[a] = static_cast<cl_int>(std::clamp(hi, 0.0, static_cast<double>(dims.s[a])));
    }
  }
  const int stride = std::max(1, spec_.mark_stride);
  cl::setArgs(mark_, *frame.depth, static_cast<cl_int>(k.width), rect_arg,
              static_cast<cl_int>(stride), static_cast<cl_float>(k.fx), static_cast<cl_float>(k.fy),
              static_cast<cl_float>(k.cx), static_cast<cl_float>(k.cy), row4(T_volume_camera, 0),
              row4(T_volume_camera, 1), row4(T_volume_camera, 2), static_cast<cl_float>(block_m),
              static_cast<cl_float>(spec_.truncation_m), dims, mark_lo, mark_hi, needed_, state_);
  // ctx_.lanes() pixels of a row per work item, every stride-th pixel and row.
  if (!rect.empty()) {
    const int columns = (rect.width + stride - 1) / stride;
    cl::enqueue(ctx_.queue(), mark_,
                static_cast<size_t>((columns + ctx_.lanes() - 1) / ctx_.lanes()),
                static_cast<size_t>((rect.height + stride - 1) / stride), 0, 4, 16);
  }

  const cl_int block_count = spec_.blockCount();
  const cl_int phases = std::max(1, spec_.integrate_every);
  const cl_int phase = static_cast<cl_int>(allocations_++ % phases);
  cl::setArgs(assign_, needed_, index_, countIndex(), static_cast<cl_int>(spec_.has_counts),
              block_count, dims, static_cast<cl_int>(spec_.integrate_all_blocks), phases, phase,
              pool_.freeList(), pool_.state(), state_, block_list_);
  cl::enqueue(ctx_.queue(), assign_,
              static_cast<size_t>((block_count + kAssignGroup - 1) / kAssignGroup), 0, 0, 64);
  cl::setArgs(finalize_, pool_.state(), state_);
  cl::enqueue(ctx_.queue(), finalize_, 1);
  ctx_.read(state_, report_, sizeof(report_), kVolumeReport * sizeof(int32_t));
  last_report_.listed_blocks = report_[0];
  last_report_.allocated_blocks = report_[1];
  last_report_.dropped_blocks = report_[2];
  last_report_.new_blocks = report_[3];
  last_report_.outside_pixels = report_[4] * stride * stride;
  last_report_.phase = phase;
  pool_.recordAllocation(last_report_.dropped_blocks);
  return last_report_;
}

void Volume::integrate(const IntegrationInput& frame) {
  checkFrame(frame, "Volume::integrate");
  if (last_report_.listed_blocks == 0) return;
  const PoseRows T_camera_volume = PoseRows::from(frame.T_world_camera.inverse() * T_world_volume_);
  const core::Intrinsics& k = frame.intrinsics;
  const size_t blocks = static_cast<size_t>(last_report_.listed_blocks);
  cl::setArgs(
      integrate_, block_list_, index_, dimsBlocks(), pool_.voxels(), *frame.depth,
      frame.weights ? *frame.weights : pool_.dummy(), static_cast<cl_int>(frame.weights != nullptr),
      static_cast<cl_int>(k.width), static_cast<cl_int>(k.height), static_cast<cl_float>(k.fx),
      static_cast<cl_float>(k.fy), static_cast<cl_float>(k.cx), static_cast<cl_float>(k.cy),
      row4(T_camera_volume, 0), row4(T_camera_volume, 1), row4(T_camera_volume, 2),
      static_cast<cl_float>(spec_.voxel_size_m), static_cast<cl_float>(spec_.truncation_m),
      static_cast<cl_float>(1.0f / spec_.truncation_m), static_cast<cl_float>(spec_.max_weight),
      static_cast<cl_int>(spec_.free_space_full_weight), static_cast<cl_int>(spec_.behind_dropoff),
      static_cast<cl_float>(std::max(1, spec_.integrate_every)));
  // ctx_.lanes() voxels per work item.
  const size_t items = static_cast<size_t>(kBlockVoxels / ctx_.lanes());
  cl::enqueue(ctx_.queue(), integrate_, blocks * items, 0, 0, items);
  if (spec_.has_counts && frame.fg_mask) {
    cl::setArgs(count_, block_list_, count_index_, dimsBlocks(), pool_.voxels(), *frame.depth,
                *frame.fg_mask, static_cast<cl_int>(k.width), static_cast<cl_int>(k.height),
                static_cast<cl_float>(k.fx), static_cast<cl_float>(k.fy),
                static_cast<cl_float>(k.cx), static_cast<cl_float>(k.cy), row4(T_camera_volume, 0),
                row4(T_camera_volume, 1), row4(T_camera_volume, 2),
                static_cast<cl_float>(spec_.voxel_size_m),
                static_cast<cl_float>(spec_.truncation_m));
    cl::enqueue(ctx_.queue(), count_, blocks * kCountGroup, 0, 0, kCountGroup);
  }
}

AllocationReport Volume::fuse(const IntegrationInput& frame) {
  const AllocationReport r = allocate(frame);
  integrate(frame);
  return r;
}

void Volume::clear() {
  const cl_int block_count = spec_.blockCount();
  cl::setArgs(release_, index_, countIndex(), static_cast<cl_int>(spec_.has_counts), block_count,
              pool_.freeList(), pool_.state(), pool_.voxels());
  cl::enqueue(ctx_.queue(), release_, static_cast<size_t>(block_count), 0, 0, 256);
  const int32_t zero_state[kVolumeStateInts] = {};
  ctx_.write(state_, zero_state, sizeof(zero_state));
  last_report_ = AllocationReport{};
}

void Volume::grow(const Eigen::Vector3i& add_low_blocks, const Eigen::Vector3i& add_high_blocks) {
  if ((add_low_blocks.array() < 0).any() || (add_high_blocks.array() < 0).any()) {
    throw InvalidArgument("Volume::grow: block counts must be >= 0");
  }
  const Eigen::Vector3i old_dims = spec_.dims_blocks;
  const Eigen::Vector3i new_dims = old_dims + add_low_blocks + add_high_blocks;
  if (static_cast<int64_t>(new_dims.x()) * new_dims.y() * new_dims.z() > kMaxGridBlocks) {
    throw InvalidArgument("Volume::grow: a grid of " + dimsText(new_dims) +
                          " blocks is larger than " + std::to_string(kMaxGridBlocks) + " blocks");
  }
  if (new_dims == old_dims) return;
  cl::MemHandle old_index = index_;
  cl::MemHandle old_count_index = count_index_;
  const cl_int4 old_dims_cl = dimsBlocks();
  spec_.dims_blocks = new_dims;
  createBuffers();
  const cl_int4 new_dims_cl = dimsBlocks();
  const cl_int4 offset{{add_low_blocks.x(), add_low_blocks.y(), add_low_blocks.z(), 0}};
  const size_t n = static_cast<size_t>(spec_.blockCount());
  cl::setArgs(reindex_, old_index, old_dims_cl, index_, new_dims_cl, offset);
  cl::enqueue(ctx_.queue(), reindex_, n, 0, 0, 256);
  if (spec_.has_counts) {
    cl::setArgs(reindex_, old_count_index, old_dims_cl, count_index_, new_dims_cl, offset);
    cl::enqueue(ctx_.queue(), reindex_, n, 0, 0, 256);
  }
  ctx_.finish();
  Eigen::Isometry3d shift = Eigen::Isometry3d::Identity();
  shift.translation() = -add_low_blocks.cast<double>() *
                        (static_cast<double>(kBlockSize) * static_cast<double>(spec_.voxel_size_m));
  T_world_volume_ = T_world_volume_ * shift;
  T_volume_initial_ = shift.inverse() * T_volume_initial_;
  last_report_.listed_blocks = 0;  // the block list was for the old grid: allocate() again
}

int Volume::shift(const Eigen::Vector3i& blocks) {
  if (spec_.has_counts) {
    throw InvalidArgument("Volume::shift: only volumes without counts (the background) shift");
  }
  if (blocks.isZero()) return 0;
  const cl_int4 dims = dimsBlocks();
  const cl_int4 by{{blocks.x(), blocks.y(), blocks.z(), 0}};
  const size_t n = static_cast<size_t>(spec_.blockCount());
  int32_t before = 0, after = 0;
  ctx_.read(state_, &before, sizeof(before), 1 * sizeof(int32_t));  // EMF_VOL_ALLOCATED
  cl::setArgs(evict_, index_, dims, by, pool_.freeList(), pool_.state(), pool_.voxels(), state_);
  cl::enqueue(ctx_.queue(), evict_, n, 0, 0, 256);
  // New entry b = old entry b + blocks, through the block list (an int per block, free between
  // frames) so that no buffer is allocated.
  const cl_int4 offset{{-blocks.x(), -blocks.y(), -blocks.z(), 0}};
  cl::setArgs(reindex_, index_, dims, block_list_, dims, offset);
  cl::enqueue(ctx_.queue(), reindex_, n, 0, 0, 256);
  EMF_CL_CHECK(clEnqueueCopyBuffer(ctx_.queue(), block_list_.get(), index_.get(), 0, 0,
                                   n * sizeof(int32_t), 0, nullptr, nullptr));
  ctx_.read(state_, &after, sizeof(after), 1 * sizeof(int32_t));
  Eigen::Isometry3d move = Eigen::Isometry3d::Identity();
  move.translation() = blocks.cast<double>() *
                       (static_cast<double>(kBlockSize) * static_cast<double>(spec_.voxel_size_m));
  T_world_volume_ = T_world_volume_ * move;
  T_volume_initial_ = move.inverse() * T_volume_initial_;
  last_report_.allocated_blocks = after;
  last_report_.listed_blocks = 0;  // the block list held the re-indexing: allocate() again
  return before - after;
}

VolumeHostData Volume::download(const BlockFilter& keep) const {
  VolumeHostData out;
  out.dims_blocks = spec_.dims_blocks;
  out.voxel_size_m = spec_.voxel_size_m;
  out.truncation_m = spec_.truncation_m;
  out.T_world_volume = T_world_volume_;
  out.T_volume_initial = T_volume_initial_;
  const size_t n = static_cast<size_t>(spec_.blockCount());
  std::vector<int32_t> index(n), count_index;
  ctx_.read(index_, index.data(), n * sizeof(int32_t));
  if (spec_.has_counts) {
    count_index.resize(n);
    ctx_.read(count_index_, count_index.data(), n * sizeof(int32_t));
  }
  if (keep) {
    for (size_t i = 0; i < n; ++i) {
      if ((index[i] >= 0 || (!count_index.empty() && count_index[i] >= 0)) &&
          !keep(blockCoords(spec_.dims_blocks, static_cast<int>(i)))) {
        index[i] = -1;
        if (!count_index.empty()) count_index[i] = -1;
      }
    }
  }
  // Pool slots in use, sorted; read them in contiguous runs.
  std::vector<int32_t> slots;
  for (int32_t s : index) {
    if (s >= 0) slots.push_back(s);
  }
  for (int32_t s : count_index) {
    if (s >= 0) slots.push_back(s);
  }
  std::sort(slots.begin(), slots.end());
  slots.erase(std::unique(slots.begin(), slots.end()), slots.end());
  std::map<int32_t, int32_t> compact;
  out.voxels.resize(slots.size() * kBlockVoxels);
  for (size_t i = 0; i < slots.size();) {
    size_t j = i + 1;
    while (j < slots.size() && slots[j] == slots[j - 1] + 1) ++j;
    ctx_.read(pool_.voxels(), out.voxels.data() + i * kBlockVoxels, (j - i) * VoxelPool::kSlotBytes,
              static_cast<size_t>(slots[i]) * VoxelPool::kSlotBytes);
    i = j;
  }
  for (size_t i = 0; i < slots.size(); ++i) compact[slots[i]] = static_cast<int32_t>(i);
  out.pool_slots = slots;
  out.index.resize(n);
  for (size_t i = 0; i < n; ++i) out.index[i] = index[i] >= 0 ? compact[index[i]] : -1;
  if (spec_.has_counts) {
    out.count_index.resize(n);
    for (size_t i = 0; i < n; ++i) {
      out.count_index[i] = count_index[i] >= 0 ? compact[count_index[i]] : -1;
    }
  }
  return out;
}

}  // namespace emf::map
