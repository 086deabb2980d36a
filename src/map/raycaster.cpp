#include "map/raycaster.h"

#include <opencv2/imgproc.hpp>
#include <string>

#include "common/error.h"
#include "map/map_math.h"

namespace emf::map {

namespace {
cl_float4 row4(const PoseRows& p, int i) {
  return cl_float4{{p.r[i][0], p.r[i][1], p.r[i][2], p.r[i][3]}};
}
}  // namespace

RayCaster::RayCaster(cl::Context& ctx, const MapOptions& options, int max_width, int max_height)
    : ctx_(ctx), options_(options), max_width_(max_width), max_height_(max_height) {
  if (max_width <= 0 || max_height <= 0) {
    throw InvalidArgument("RayCaster needs a positive image size");
  }
  const size_t n = static_cast<size_t>(max_width) * static_cast<size_t>(max_height);
  depth_ = ctx_.buffer(CL_MEM_READ_WRITE, n * sizeof(float));
  normals_ = ctx_.buffer(CL_MEM_READ_WRITE, n * sizeof(cl_float4));
  ids_ = ctx_.buffer(CL_MEM_READ_WRITE, n * sizeof(cl_int));
  const size_t tiles = static_cast<size_t>((max_width + kRayTile - 1) / kRayTile) *
                       static_cast<size_t>((max_height + kRayTile - 1) / kRayTile);
  tile_min_ = ctx_.buffer(CL_MEM_READ_WRITE, tiles * sizeof(cl_int));
  tile_max_ = ctx_.buffer(CL_MEM_READ_WRITE, tiles * sizeof(cl_int));
  clear_ = ctx_.kernel("raycast", "raycast_clear");
  clear_bounds_ = ctx_.kernel("raycast", "raycast_clear_bounds");
  bounds_ = ctx_.kernel("raycast", "raycast_bounds");
  cast_ = ctx_.kernel("raycast", "raycast_volume_lanes");
}

void RayCaster::render(const std::vector<RenderItem>& volumes, const core::Intrinsics& k,
                       const Eigen::Isometry3d& T_world_camera) {
  if (!k.valid() || k.width > max_width_ || k.height > max_height_) {
    throw InvalidArgument("RayCaster::render: image " + std::to_string(k.width) + "x" +
                          std::to_string(k.height) + " is invalid or larger than the " +
                          std::to_string(max_width_) + "x" + std::to_string(max_height_) +
                          " allocated at start-up");
  }
  width_ = k.width;
  height_ = k.height;
  const cl_int n = width_ * height_;
  const cl_int tiles_x = (width_ + kRayTile - 1) / kRayTile;
  const cl_int tiles = tiles_x * ((height_ + kRayTile - 1) / kRayTile);
  cl::setArgs(clear_, depth_, normals_, ids_, n);
  cl::enqueue(ctx_.queue(), clear_, static_cast<size_t>(n), 0, 0, 256);
  for (const RenderItem& item : volumes) {
    if (!item.volume) throw InvalidArgument("RayCaster::render: null volume");
    const Volume& vol = *item.volume;
    const VolumeSpec& s = vol.spec();
    const PoseRows T_volume_camera =
        PoseRows::from(vol.T_world_volume().inverse() * T_world_camera);
    const PoseRows T_camera_volume =
        PoseRows::from(T_world_camera.inverse() * vol.T_world_volume());
    cl::setArgs(clear_bounds_, tile_min_, tile_max_, tiles);
    cl::enqueue(ctx_.queue(), clear_bounds_, static_cast<size_t>(tiles), 0, 0, 64);
    const cl_int blocks = s.blockCount();
    cl::setArgs(bounds_, vol.index(), vol.dimsBlocks(),
                static_cast<cl_float>(static_cast<float>(kBlockSize) * s.voxel_size_m),
                row4(T_camera_volume, 0), row4(T_camera_volume, 1), row4(T_camera_volume, 2),
                static_cast<cl_int>(width_), static_cast<cl_int>(height_),
                static_cast<cl_float>(k.fx), static_cast<cl_float>(k.fy),
                static_cast<cl_float>(k.cx), static_cast<cl_float>(k.cy),
                static_cast<cl_float>(options_.raycast_min_depth_m),
                static_cast<cl_float>(options_.raycast_max_depth_m), tiles_x, tile_min_, tile_max_);
    cl::enqueue(ctx_.queue(), bounds_, static_cast<size_t>(blocks), 0, 0, 64);
    cl::setArgs(cast_, vol.index(), vol.countIndex(), static_cast<cl_int>(s.has_counts),
                vol.dimsBlocks(), vol.pool().voxels(), static_cast<cl_float>(s.voxel_size_m),
                static_cast<cl_float>(s.truncation_m),
                static_cast<cl_float>(options_.raycast_step_fraction), row4(T_volume_camera, 0),
                row4(T_volume_camera, 1), row4(T_volume_camera, 2), static_cast<cl_int>(width_),
                static_cast<cl_int>(height_), static_cast<cl_float>(k.fx),
                static_cast<cl_float>(k.fy), static_cast<cl_float>(k.cx),
                static_cast<cl_float>(k.cy), static_cast<cl_float>(options_.raycast_min_depth_m),
                static_cast<cl_float>(options_.raycast_max_depth_m), static_cast<cl_int>(item.id),
                static_cast<cl_float>(item.depth_margin_m), tiles_x, tile_min_, tile_max_, depth_,
                normals_, ids_);
    // ctx_.lanes() pixels of a row per work item.
    cl::enqueue(ctx_.queue(), cast_,
                static_cast<size_t>((width_ + ctx_.lanes() - 1) / ctx_.lanes()),
                static_cast<size_t>(height_), 0, 4, 16);
  }
}

void RayCaster::download(cv::Mat* depth, cv::Mat* normals, cv::Mat* ids) const {
  const size_t n = static_cast<size_t>(width_) * static_cast<size_t>(height_);
  if (depth) {
    depth->create(height_, width_, CV_32FC1);
    ctx_.read(depth_, depth->ptr<float>(0), n * sizeof(float));
  }
  if (normals) {
    cv::Mat n4(height_, width_, CV_32FC4);
    ctx_.read(normals_, n4.ptr<float>(0), n * sizeof(cl_float4));
    cv::cvtColor(n4, *normals, cv::COLOR_BGRA2BGR);
  }
  if (ids) {
    ids->create(height_, width_, CV_32SC1);
    ctx_.read(ids_, ids->ptr<int>(0), n * sizeof(cl_int));
  }
}

void RayCaster::downloadTileRanges(std::vector<float>* z_min, std::vector<float>* z_max) const {
  const size_t tiles = static_cast<size_t>((width_ + kRayTile - 1) / kRayTile) *
                       static_cast<size_t>((height_ + kRayTile - 1) / kRayTile);
  z_min->resize(tiles);
  z_max->resize(tiles);
  ctx_.read(tile_min_, z_min->data(), tiles * sizeof(float));  // float bits stored as int
  ctx_.read(tile_max_, z_max->data(), tiles * sizeof(float));
}

SdfSampler::SdfSampler(cl::Context& ctx)
    : ctx_(ctx), kernel_(ctx.kernel("sdf_sample", "sample_sdf_points")) {}

void SdfSampler::sample(const Volume& volume, const cl::MemHandle& points, int count,
                        const cl::MemHandle& psi, const cl::MemHandle& weight,
                        const cl::MemHandle& gradient, const cl::MemHandle& pfg) {
  const VolumeSpec& s = volume.spec();
  cl::setArgs(kernel_, volume.index(), volume.countIndex(), static_cast<cl_int>(s.has_counts),
              volume.dimsBlocks(), volume.pool().voxels(), static_cast<cl_float>(s.voxel_size_m),
              static_cast<cl_float>(s.truncation_m), points, static_cast<cl_int>(count), psi,
              weight, gradient, pfg);
  cl::enqueue(ctx_.queue(), kernel_, static_cast<size_t>(count), 0, 0, 64);
}

}  // namespace emf::map
