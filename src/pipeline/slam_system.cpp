#include "pipeline/slam_system.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

#include "cl/work_counters.h"
#include "common/error.h"
#include "common/log.h"
#include "map/volume_host_access.h"

namespace emf::pipeline {
namespace {

/// The camera's vertex map is read only by the camera tracker, at every track.pixel_stride-th
/// pixel (coarse levels at multiples of it), unless the objects share it (objects.filter_depth):
/// the filter skips the other pixels.
int cameraSampleStride(const Config& config, int width) {
  return config.objects.filter_depth ? 1 : config.track.pixelStrideFor(width);
}

}  // namespace

const std::vector<std::string>& SlamSystem::stageNames() {
  static const std::vector<std::string> kStages = {
      "preprocess", "estep", "track", "track_objects", "detect", "objects", "integrate"};
  return kStages;
}

SlamSystem::SlamSystem(cl::Context& ctx, const Config& config, const core::Intrinsics& intrinsics,
                       const std::string& source_uri)
    : ctx_(ctx),
      config_(config),
      intrinsics_(core::checkedIntrinsics(intrinsics)),
      pool_(std::make_unique<map::VoxelPool>(ctx, config.map)),
      preprocessor_(ctx, config.preprocess, intrinsics,
                    cameraSampleStride(config, intrinsics.width)),
      tracker_(ctx, config.track, intrinsics.width, intrinsics.height),
      estep_(ctx, config.em, intrinsics.width, intrinsics.height, 1 + config.objects.max_objects),
      timer_(stageNames(), 4096),
      counters_({"track_iterations", "object_track_iterations", "object_track_pixels",
                 "integrated_blocks", "kernel_launches", "host_waits", "bytes_read"},
                4096) {
  if (!config.detector.plugin.empty()) {
    scheduler_ = std::make_unique<DetectorScheduler>(config.detector, source_uri, intrinsics);
  }
  if (scheduler_ && scheduler_->readsFeedback()) {
    const size_t pixels = static_cast<size_t>(intrinsics.width) * intrinsics.height;
    sdf_sampler_ = std::make_unique<map::SdfSampler>(ctx);
    probe_points_ = ctx.buffer(CL_MEM_READ_ONLY, pixels * sizeof(cl_float4));
    probe_psi_ = ctx.buffer(CL_MEM_WRITE_ONLY, pixels * sizeof(float));
    probe_weight_ = ctx.buffer(CL_MEM_WRITE_ONLY, pixels * sizeof(float));
    probe_gradient_ = ctx.buffer(CL_MEM_WRITE_ONLY, pixels * sizeof(cl_float4));
    probe_pfg_ = ctx.buffer(CL_MEM_WRITE_ONLY, pixels * sizeof(float));
  }
  const map::VolumeSpec spec = map::VolumeSpec::background(config.map);
  background_ = std::make_unique<map::Volume>(
      *pool_, spec, map::backgroundVolumePose(config.map, spec, Eigen::Isometry3d::Identity()));
  follow_ = map::followRule(config.map, spec);
  objects_ = std::make_unique<ObjectLifecycle>(ctx, config, intrinsics_, *pool_, *background_,
                                               preprocessor_, estep_, timer_, counters_);
  const double index_mib = static_cast<double>(background_->indexBytes()) / (1 << 20);
  logInfo("background volume: ", spec.dims_blocks.x() * map::kBlockSize, "^3 voxels of ",
          spec.voxel_size_m * 100, " cm (block index ", index_mib, " MiB); pool ",
          pool_->capacitySlots(), " slots (", config.map.memory_mb, " MiB); up to ",
          config.objects.max_objects, " objects");
  // The dense block index lives outside the pool's budget; past the pool's own size it is the
  // larger part of the memory in use (background_resolution 4096: 1.15 GiB for a 256 MiB pool).
  if (index_mib > config.map.memory_mb) {
    logWarning("the background's block index takes ", index_mib, " MiB outside map.memory_mb (",
               config.map.memory_mb, " MiB): lower map.background_resolution (",
               config.map.background_resolution,
               "; a coarser map.background_voxel_m keeps the extent) to stay near the budget");
  }
}

SlamSystem::~SlamSystem() = default;

FrameOutcome SlamSystem::process(const core::Frame& frame,
                                 const std::vector<core::Detection>* detections) {
  if (frame.depth.type() != CV_32FC1 || frame.depth.cols != intrinsics_.width ||
      frame.depth.rows != intrinsics_.height) {
    throw InvalidArgument("frame " + std::to_string(frame.index) + ": depth must be CV_32F " +
                          std::to_string(intrinsics_.width) + "x" +
                          std::to_string(intrinsics_.height) + " (the source's intrinsics), got " +
                          std::to_string(frame.depth.cols) + "x" +
                          std::to_string(frame.depth.rows));
  }
  const cl::WorkCounts work_before = cl::workCounts();
  FrameOutcome out;
  out.index = frames_;
  out.timestamp = frame.timestamp;
  out.first = frames_ == 0;
  objects_->beginFrame(frames_, frame.timestamp);
  {
    ScopedStage s(timer_, "preprocess");
    // The range guard's frame limit, once for both preprocessors (same depth range).
    const float frame_max_m = config_.preprocess.range_guard_per_m2 > 0
                                  ? track::maxDepthInRange(frame.depth, config_.preprocess)
                                  : std::numeric_limits<float>::infinity();
    preprocessor_.process(frame.depth, frame_max_m);  // also keeps the raw depth on the device
    // The objects' vertex map only when the E-step or the object rules will read it this frame.
    const bool detector_due =
        scheduler_ != nullptr &&
        (scheduler_->async() || frame.index % config_.detector.every_n_frames == 0);
    if (!objects_->empty() || detections != nullptr || detector_due) {
      objects_->preprocess(frame.depth, frame_max_m);
    }
    ctx_.finish();  // stage times include the device work
  }
  const cl_mem vertex = preprocessor_.vertexMap().get();
  if (!out.first) {
    // Constant-velocity predictions from the last tracked motions (camera and objects).
    const Eigen::Isometry3d T_world_predicted = T_world_camera_ * last_motion_;
    const std::vector<Eigen::Isometry3d> T_oc_predicted =
        objects_->posesInCamera(T_world_camera_, true);
    const bool with_objects = !objects_->empty();
    if (with_objects) {
      ScopedStage s(timer_, "estep");
      // The camera's weights: q_0 only, at the pixels the camera tracker reads.
      estep_.computeBackgroundWeights(objects_->vertexMap(),
                                      objects_->eStepVolumes(T_world_predicted, T_oc_predicted),
                                      tracker_.options().pixel_stride);
      ctx_.finish();
    }
    {
      ScopedStage s(timer_, "track");
      const Eigen::Isometry3d T_volume_init =
          background_->T_world_volume().inverse() * T_world_predicted;
      out.track = tracker_.track(deviceView(*background_), vertex,
                                 with_objects ? estep_.q(0).get() : nullptr, T_volume_init);
      counters_.add("track_iterations", out.track.iterations);
    }
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
    objects_->setCamera(T_world_camera_, last_motion_);
    if (with_objects && !out.lost) objects_->track(T_oc_predicted, feedbackDue(frame));
    if (out.lost) objects_->markAllLost();
  }
  out.T_world_camera = T_world_camera_;
  if (!out.lost) {
    std::optional<DetectionBatch> batch;
    if (detections) {
      batch.emplace();
      batch->frame_index = frame.index;
      batch->timestamp = frame.timestamp;
      batch->T_world_camera = T_world_camera_;
      batch->detections = *detections;
    } else if (scheduler_) {
      ScopedStage s(timer_, "detect");
      batch = runDetector(frame);
    }
    if (batch) {
      ScopedStage s(timer_, "objects");
      out.detector_ran = true;
      out.detections = objects_->matchDetections(*batch, &out.matches);
      objects_->createObjects();
    }
    {
      ScopedStage s(timer_, "integrate");
      map::IntegrationInput in;
      in.depth = &preprocessor_.inputDepth();  // raw depth (metres, NaN invalid)
      in.intrinsics = intrinsics_;
      in.T_world_camera = T_world_camera_;
      in.weights = objects_->backgroundWeights();
      if (config_.map.follow_camera) followCamera(&out);
      out.allocation = integrateBackground(in);
      objects_->integrate(in);
      ctx_.finish();
    }
    {
      ScopedStage s(timer_, "objects");
      objects_->applyRules(out.detector_ran, frame.depth);
    }
  }
  objects_->keepTentativePoses();
  out.objects = objects_->outcomes();
  out.confirmed = objects_->takeConfirmed();
  // The OpenCL work of this frame (process-wide counts: a detector thread of the async mode
  // using emf's cl wrappers would be counted here too; the plugins use their own runtimes).
  const cl::WorkCounts work = cl::workCounts();
  counters_.add("kernel_launches", static_cast<double>(work.launches - work_before.launches));
  counters_.add("host_waits", static_cast<double>(work.host_waits - work_before.host_waits));
  counters_.add("bytes_read", static_cast<double>(work.bytes_read - work_before.bytes_read));
  timer_.endFrame();
  counters_.endFrame();
  ++frames_;
  return out;
}

map::AllocationReport SlamSystem::integrateBackground(const map::IntegrationInput& in) {
  const map::AllocationReport report = background_->fuse(in);
  counters_.add("integrated_blocks", report.listed_blocks);
  if (report.dropped_blocks > 0) {
    // Logged the first time and every 100th frame: a full pool is a state, not an event.
    if (background_pool_full_frames_++ % 100 == 0) {
      logWarning("frame ", frames_, ": voxel pool full: ", report.dropped_blocks,
                 " background blocks found no slot (", background_pool_full_frames_,
                 " frame(s) so far); the map is incomplete and tracking may drift: raise "
                 "map.memory_mb (",
                 config_.map.memory_mb, " MiB) or coarsen map.background_voxel_m");
    }
  }
  return report;
}

void SlamSystem::followCamera(FrameOutcome* out) {
  // Only while the camera sees past the grid (the last allocation's count of pixels whose
  // surface fell outside it): a scene that fits in the grid never moves it.
  const double outside = static_cast<double>(background_->lastReport().outside_pixels) /
                         (static_cast<double>(intrinsics_.width) * intrinsics_.height);
  if (!(outside > config_.map.follow_outside_fraction)) return;
  const Eigen::Vector3i blocks = map::followShift(
      background_->spec(), background_->T_world_volume(), T_world_camera_, follow_);
  if (blocks.isZero()) return;
  if (!evicted_) {
    std::string folder = evicted_folder_;
    if (folder.empty()) {
      std::error_code ec;
      folder = std::filesystem::temp_directory_path(ec).string();
    }
    evicted_ = std::make_unique<EvictedSurface>(folder);
  }
  evicted_->add(*background_, blocks);  // copies what leaves; meshed on the worker thread
  out->map_shift = blocks;
  out->evicted_blocks = background_->shift(blocks);
  ++shifts_;
  evicted_blocks_ += out->evicted_blocks;
  logDebug("frame ", frames_, ": background moved by (", blocks.x(), ", ", blocks.y(), ", ",
           blocks.z(), ") blocks, ", out->evicted_blocks, " blocks left it");
}

namespace {
/// Offsets the triangle indices of a mesh streamed after `base` vertices.
class OffsetSink : public map::MeshSink {
 public:
  OffsetSink(map::MeshSink& target, size_t base) : target_(target), base_(base) {}
  void addVertices(const Eigen::Vector3f* positions, const Eigen::Vector3f* normals,
                   size_t count) override {
    target_.addVertices(positions, normals, count);
  }
  void addTriangles(const Eigen::Vector3i* triangles, size_t count) override {
    if (base_ == 0) return target_.addTriangles(triangles, count);
    shifted_.assign(triangles, triangles + count);
    for (Eigen::Vector3i& t : shifted_) t.array() += static_cast<int>(base_);
    target_.addTriangles(shifted_.data(), count);
  }

 private:
  map::MeshSink& target_;
  size_t base_;
  std::vector<Eigen::Vector3i> shifted_;
};
}  // namespace

void SlamSystem::extractBackgroundMesh(map::MeshSink& sink) const {
  const size_t base = evicted_ ? evicted_->replay(sink) : 0;
  OffsetSink offset(sink, base);
  const map::VolumeHostAccess access(*background_);
  map::extractMesh(access.view(), access.T_world_volume(), map::MeshOptions(), offset);
}

DetectorStats SlamSystem::detectorStats() const {
  return scheduler_ ? scheduler_->stats() : DetectorStats{};
}

bool SlamSystem::feedbackDue(const core::Frame& frame) const {
  return scheduler_ && scheduler_->readsFeedback() &&
         (scheduler_->async() || frame.index % config_.detector.every_n_frames == 0);
}

std::optional<DetectionBatch> SlamSystem::runDetector(const core::Frame& frame) {
  // Feedback for detectors that read the SLAM's state (motion): the background association and
  // the residual, on the frames the detector may run on.
  const bool feedback = feedbackDue(frame);
  cv::Mat q0, residual;
  if (feedback) detectorFeedback(&q0, &residual);
  const std::vector<ObjectPose> poses = objects_->poses();
  return scheduler_->submit(frame, T_world_camera_, feedback ? &q0 : nullptr,
                            feedback ? &residual : nullptr, &poses);
}

std::vector<ObjectOutcome> SlamSystem::objects() const {
  std::vector<ObjectOutcome> alive;
  for (auto& o : objects_->outcomes()) {
    if (o.state != ObjectState::kDeleted) alive.push_back(std::move(o));
  }
  return alive;
}

const map::Volume* SlamSystem::volume(int id) const {
  if (id == 0) return background_.get();
  return objects_->volume(id);
}

std::vector<map::RenderItem> SlamSystem::renderItems() const {
  std::vector<map::RenderItem> items;
  map::RenderItem bg;
  bg.volume = background_.get();
  bg.id = 0;
  items.push_back(bg);
  objects_->addRenderItems(&items);
  return items;
}

SlamSystem::Associations SlamSystem::associations() const {
  Associations a;
  if (objects_->eStepIds().empty()) return a;
  a.ids = objects_->eStepIds();
  for (size_t i = 0; i < a.ids.size(); ++i) a.q.push_back(estep_.downloadQ(static_cast<int>(i)));
  return a;
}

}  // namespace emf::pipeline
