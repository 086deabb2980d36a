#include "pipeline/slam_system.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "cl/work_counters.h"
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

track::TrackOptions objectTrackOptions(const Config& config, int image_width) {
  track::TrackOptions o = config.track;
  o.huber_truncation_factor = config.objects.huber_truncation_factor;
  // The data term grows with the pixel count: the prior, given for 640x480, with the area.
  const double area_scale = (image_width / 640.0) * (image_width / 640.0);
  o.prior_rotation_weight = config.objects.motion_prior_rotation * area_scale;
  // An object volume is mostly unobserved space around the object, and every pixel inside it
  // has some association q > 0: the fraction of pixels landing on observed map says nothing
  // about the object. Its loss is judged by inliers, conditioning, motion and convergence.
  o.min_valid_fraction = 0.0;
  // A small object's inliers are fewer and its silhouette pixels land off the model more
  // often than the background's: the camera's stricter inlier rules would drop good frames.
  o.min_inlier_ratio = std::min(o.min_inlier_ratio, 0.5);
  o.recovery_min_inlier_ratio = o.min_inlier_ratio;
  // Objects cover few pixels: all of them are used at the finest level.
  o.pixel_stride = 1;
  // Rotations about the object's own points: the camera is metres away from a small object, and
  // rotations about a far centre couple rotation and translation
  // (docs/method.md#object-tracking).
  o.rotation_centre = "stiffness";
  // The map-confidence weight W(p) varies strongly across a small, partly observed model:
  // accepting steps by the cost change made LM crawl and stall at the prediction
  // (TrackOptions::step_acceptance).
  o.step_acceptance = "fixed_weights";
  return o;
}

track::TrackOptions reidTrackOptions(const Config& config, int image_width) {
  track::TrackOptions o = objectTrackOptions(config, image_width);
  // A fit starts from a guess (a heading step, the detection's centroid): how far it moves says
  // nothing; the fit is judged by its inliers and overlap (object_reid.cpp). The motion prior
  // would pull towards the guess.
  o.max_motion_m = 100.0;
  o.max_motion_deg = 180.0;
  o.prior_rotation_weight = 0.0;
  return o;
}

track::PreprocessOptions objectPreprocessOptions(const Config& config) {
  track::PreprocessOptions o = config.preprocess;
  if (!config.objects.filter_depth) {
    o.bilateral_radius_px = config.objects.depth_filter_radius_px;
    o.sigma_depth_m = config.objects.depth_filter_sigma_m;
    // The objects' range sigma stays fixed: growing it with depth as the camera's blends
    // silhouettes at low resolution (docs/method.md#preprocessing).
    o.sigma_depth_per_m2 = 0.0;
    o.hole_margin_px = config.objects.depth_hole_margin_px;
  }
  return o;
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
    case ObjectState::kDormant:
      return "dormant";
  }
  return "?";
}

namespace {
/// `o` with its pixel thresholds (given for 640x480 images) scaled to an image `scale` times as
/// wide: lengths with the scale, areas with its square.
em::ObjectOptions scaledPixelThresholds(em::ObjectOptions o, double scale) {
  o.min_detection_px = static_cast<int>(std::lround(o.min_detection_px * scale));
  o.visibility_border_px = static_cast<int>(std::lround(o.visibility_border_px * scale));
  o.invisible_min_px = static_cast<int>(std::lround(o.invisible_min_px * scale * scale));
  return o;
}
}  // namespace

const std::vector<std::string>& SlamSystem::stageNames() {
  static const std::vector<std::string> kStages = {
      "preprocess", "estep", "track", "track_objects", "detect", "objects", "integrate"};
  return kStages;
}

SlamSystem::SlamSystem(cl::Context& ctx, const Config& config, const io::Intrinsics& intrinsics,
                       const std::string& source_uri)
    : ctx_(ctx),
      config_(config),
      intrinsics_(io::checkedIntrinsics(intrinsics)),
      pool_(std::make_unique<map::VoxelPool>(ctx, config.map)),
      preprocessor_(ctx, config.preprocess, intrinsics),
      object_preprocessor_(ctx, objectPreprocessOptions(config), intrinsics),
      tracker_(ctx, config.track, intrinsics.width, intrinsics.height),
      object_tracker_(ctx, objectTrackOptions(config, intrinsics.width), intrinsics.width,
                      intrinsics.height),
      reid_tracker_(ctx, reidTrackOptions(config, intrinsics.width), intrinsics.width,
                    intrinsics.height),
      estep_(ctx, config.em, intrinsics.width, intrinsics.height, 1 + config.objects.max_objects),
      raycaster_(ctx, config.map, intrinsics.width, intrinsics.height),
      timer_(stageNames(), 4096),
      counters_({"track_iterations", "object_track_iterations", "object_track_pixels",
                 "integrated_blocks", "kernel_launches", "host_waits", "bytes_read"},
                4096) {
  // Pixel thresholds of the object rules are given for 640x480 images: scale them to the frame,
  // and for the visibility rule to the size of its ray cast.
  config_.objects = scaledPixelThresholds(config.objects, intrinsics.width / 640.0);
  const int frame_width = intrinsics_.width;
  const int vis_width = config.objects.visibility_width > 0
                            ? std::min(config.objects.visibility_width, frame_width)
                            : frame_width;
  const int vis_height =
      std::max(1, static_cast<int>(std::lround(static_cast<double>(intrinsics_.height) * vis_width /
                                               frame_width)));
  visibility_k_ =
      vis_width == frame_width ? intrinsics_ : intrinsics_.scaled(vis_width, vis_height);
  visibility_options_ = scaledPixelThresholds(config.objects, vis_width / 640.0);
  // The leaving test's wide view: the frame at half its resolution in the middle of a cast of
  // the frame's size (the ray caster's capacity), twice its field of view across.
  const int inner_w = std::max(1, intrinsics_.width / 2),
            inner_h = std::max(1, intrinsics_.height / 2);
  wide_frame_ = cv::Rect((intrinsics_.width - inner_w) / 2, (intrinsics_.height - inner_h) / 2,
                         inner_w, inner_h);
  wide_k_ = intrinsics_.scaled(inner_w, inner_h);
  wide_k_.cx += wide_frame_.x;
  wide_k_.cy += wide_frame_.y;
  wide_k_.width = intrinsics_.width;
  wide_k_.height = intrinsics_.height;
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
  const size_t image_bytes = sizeof(float) * static_cast<size_t>(intrinsics.width) *
                             static_cast<size_t>(intrinsics.height);
  fg_mask_ = ctx.buffer(CL_MEM_READ_ONLY, image_bytes);
  new_weights_ = ctx.buffer(CL_MEM_READ_ONLY, image_bytes);
  reid_q_ = ctx.buffer(CL_MEM_READ_ONLY, image_bytes);
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

FrameOutcome SlamSystem::process(const io::Frame& frame,
                                 const std::vector<io::Detection>* detections) {
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
  pending_fg_.clear();
  estep_ids_.clear();
  unmatched_.clear();
  created_mask_.release();
  deleted_now_.clear();
  confirmed_now_.clear();
  frame_timestamp_ = frame.timestamp;
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
    if (!config_.objects.filter_depth &&
        (!objects_.empty() || detections != nullptr || detector_due)) {
      object_preprocessor_.process(frame.depth, frame_max_m);
    }
    ctx_.finish();  // stage times include the device work
  }
  const cl_mem vertex = preprocessor_.vertexMap().get();
  if (!out.first) {
    // Constant-velocity predictions from the last tracked motions (camera and objects).
    const Eigen::Isometry3d T_world_predicted = T_world_camera_ * last_motion_;
    std::vector<Eigen::Isometry3d> T_oc_predicted;
    for (const auto& o : objects_) {
      T_oc_predicted.push_back(o.volume->T_world_volume().inverse() * T_world_camera_ *
                               o.last_motion);
    }
    const bool with_objects = !objects_.empty();
    if (with_objects) {
      ScopedStage s(timer_, "estep");
      estep_.compute(objectVertexMap(), eStepVolumes(T_world_predicted, T_oc_predicted));
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
    if (with_objects && !out.lost) trackObjects(T_oc_predicted);
    if (out.lost) {
      for (auto& o : objects_) o.state = ObjectState::kLost;
    }
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
      matchDetections(*batch, &out);
      createObjects();
    }
    {
      ScopedStage s(timer_, "integrate");
      integrateAll();
      out.allocation = background_->lastReport();
      ctx_.finish();
    }
    {
      ScopedStage s(timer_, "objects");
      if (out.detector_ran) deleteByExistence();
      if (!objects_.empty()) checkVisibility(frame.depth);
      expireDormant();
    }
  }
  // Tentative objects keep their tracked poses for the outputs until they are confirmed.
  for (TrackedObject& o : objects_) {
    if (o.confirmed || o.state != ObjectState::kTracked) continue;
    o.earlier.push_back(
        {frames_, frame.timestamp, o.volume->T_world_initial().inverse() * T_world_camera_});
  }
  fillObjectOutcomes(&out);
  out.confirmed = std::move(confirmed_now_);
  confirmed_now_.clear();
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

cl_mem SlamSystem::objectVertexMap() const {
  return config_.objects.filter_depth ? preprocessor_.vertexMap().get()
                                      : object_preprocessor_.vertexMap().get();
}

DetectorStats SlamSystem::detectorStats() const {
  return scheduler_ ? scheduler_->stats() : DetectorStats{};
}

std::optional<DetectionBatch> SlamSystem::runDetector(const io::Frame& frame) {
  // Feedback for detectors that read the SLAM's state (motion): the background association and
  // the residual, on the frames the detector may run on.
  const bool feedback = scheduler_->readsFeedback() &&
                        (scheduler_->async() || frame.index % config_.detector.every_n_frames == 0);
  cv::Mat q0, residual;
  if (feedback) detectorFeedback(&q0, &residual);
  std::vector<ObjectPose> poses;
  for (const auto& o : objects_) poses.push_back({o.id, o.volume->T_world_volume()});
  return scheduler_->submit(frame, T_world_camera_, feedback ? &q0 : nullptr,
                            feedback ? &residual : nullptr, &poses);
}

std::vector<ObjectOutcome> SlamSystem::objects() const {
  FrameOutcome out;
  fillObjectOutcomes(&out);
  std::vector<ObjectOutcome> alive;
  for (auto& o : out.objects) {
    if (o.state != ObjectState::kDeleted) alive.push_back(std::move(o));
  }
  return alive;
}

const map::Volume* SlamSystem::volume(int id) const {
  if (id == 0) return background_.get();
  for (const auto* list : {&objects_, &dormant_}) {
    for (const auto& o : *list) {
      if (o.id == id) return o.volume.get();
    }
  }
  return nullptr;
}

std::vector<map::RenderItem> SlamSystem::renderItems() const {
  std::vector<map::RenderItem> items;
  map::RenderItem bg;
  bg.volume = background_.get();
  bg.id = 0;
  items.push_back(bg);
  for (const auto& o : objects_) {
    if (!o.rendered) continue;
    map::RenderItem it;
    it.volume = o.volume.get();
    it.id = o.id;
    it.depth_margin_m = static_cast<float>(config_.objects.render_margin_m);
    items.push_back(it);
  }
  return items;
}

SlamSystem::Associations SlamSystem::associations() const {
  Associations a;
  if (estep_ids_.empty()) return a;
  a.ids = estep_ids_;
  for (size_t i = 0; i < estep_ids_.size(); ++i)
    a.q.push_back(estep_.downloadQ(static_cast<int>(i)));
  a.residual = estep_.downloadResidual();
  return a;
}

}  // namespace emf::pipeline
