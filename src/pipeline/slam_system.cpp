#include "pipeline/slam_system.h"

#include "common/error.h"
#include "common/log.h"

namespace emf::pipeline {

map::VolumeDeviceView deviceView(const map::Volume& volume) {
  map::VolumeDeviceView v;
  v.index = volume.index().get();
  v.dims_blocks = volume.spec().dims_blocks;
  v.voxels = volume.pool().voxels().get();
  v.voxel_size_m = volume.spec().voxel_size_m;
  v.truncation_m = volume.spec().truncation_m;
  return v;
}

const std::vector<std::string>& SlamSystem::stageNames() {
  static const std::vector<std::string> kStages = {"preprocess", "track", "integrate"};
  return kStages;
}

const char* objectStateName(ObjectState state) {
  switch (state) {
    case ObjectState::kTracked:
      return "tracked";
    case ObjectState::kLost:
      return "lost";
    case ObjectState::kInvisible:
      return "invisible";
    case ObjectState::kDeleted:
      return "deleted";
  }
  return "?";
}

SlamSystem::SlamSystem(cl::Context& ctx, const Config& config, const io::Intrinsics& intrinsics,
                       const std::string& /*source_uri*/)
    : ctx_(ctx),
      config_(config),
      intrinsics_(intrinsics),
      pool_(std::make_unique<map::VoxelPool>(ctx, config.map)),
      preprocessor_(ctx, config.preprocess, intrinsics),
      tracker_(ctx, config.track, intrinsics.width, intrinsics.height),
      timer_(stageNames(), 4096) {
  const map::VolumeSpec spec = map::VolumeSpec::background(config.map);
  background_ = std::make_unique<map::Volume>(
      *pool_, spec, map::backgroundVolumePose(config.map, spec, Eigen::Isometry3d::Identity()));
  logInfo("background volume: ", spec.dims_blocks.x() * map::kBlockSize, "^3 voxels of ",
          spec.voxel_size_m * 100, " cm; pool ", pool_->capacitySlots(), " blocks (",
          config.map.memory_mb, " MiB)");
}

FrameOutcome SlamSystem::process(const io::Frame& frame) {
  if (frame.depth.type() != CV_32FC1 || frame.depth.cols != intrinsics_.width ||
      frame.depth.rows != intrinsics_.height) {
    throw InvalidArgument("frame " + std::to_string(frame.index) + ": depth must be CV_32F " +
                          std::to_string(intrinsics_.width) + "x" +
                          std::to_string(intrinsics_.height) + " (the source's intrinsics), got " +
                          std::to_string(frame.depth.cols) + "x" +
                          std::to_string(frame.depth.rows));
  }
  FrameOutcome out;
  out.index = frames_;
  out.timestamp = frame.timestamp;
  out.first = frames_ == 0;
  {
    ScopedStage s(timer_, "preprocess");
    preprocessor_.process(frame.depth);  // also keeps the raw depth on the device
    ctx_.finish();                       // stage times include the device work
  }
  if (!out.first) {
    ScopedStage s(timer_, "track");
    // Constant-velocity prediction from the last tracked motion.
    const Eigen::Isometry3d T_world_predicted = T_world_camera_ * last_motion_;
    const Eigen::Isometry3d T_volume_init =
        background_->T_world_volume().inverse() * T_world_predicted;
    out.track = tracker_.track(deviceView(*background_), preprocessor_.vertexMap().get(), nullptr,
                               T_volume_init);
    if (out.track.lost) {
      out.lost = true;
      out.loss_reason = out.track.loss_reason;
      ++lost_;
      last_motion_ = Eigen::Isometry3d::Identity();
    } else {
      const Eigen::Isometry3d T_world_new =
          background_->T_world_volume() * out.track.T_volume_camera;
      last_motion_ = T_world_camera_.inverse() * T_world_new;
      T_world_camera_ = T_world_new;
    }
  }
  out.T_world_camera = T_world_camera_;
  if (!out.lost) {
    ScopedStage s(timer_, "integrate");
    map::IntegrationInput in;
    in.depth = &preprocessor_.inputDepth();  // raw depth (metres, NaN invalid)
    in.intrinsics = intrinsics_;
    in.T_world_camera = T_world_camera_;
    out.allocation = background_->fuse(in);
    ctx_.finish();
  }
  timer_.endFrame();
  ++frames_;
  return out;
}

std::vector<ObjectOutcome> SlamSystem::objects() const { return {}; }

const map::Volume* SlamSystem::volume(int id) const {
  return id == 0 ? background_.get() : nullptr;
}

std::vector<map::RenderItem> SlamSystem::renderItems() const {
  map::RenderItem bg;
  bg.volume = background_.get();
  bg.id = 0;
  return {bg};
}

}  // namespace emf::pipeline
