#include "pipeline/object_lifecycle.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <string>

#include "common/log.h"
#include "pipeline/object_points.h"
#include "pipeline/scene_up.h"

namespace emf::pipeline {

map::VolumeDeviceView deviceView(const map::Volume& volume) {
  map::VolumeDeviceView v;
  v.index = volume.index().get();
  v.dims_blocks = volume.spec().dims_blocks;
  v.voxels = volume.pool().voxels().get();
  v.voxel_size_m = volume.spec().voxel_size_m;
  v.truncation_m = volume.spec().truncation_m;
  v.volume_key = volume.key();
  return v;
}

Eigen::AlignedBox3d TrackedObject::claimInVolume() const {
  Eigen::AlignedBox3d claim;  // empty
  if (claim_initial.isEmpty()) return claim;
  const Eigen::Isometry3d& T_volume_initial = volume->T_volume_initial();
  for (int c = 0; c < 8; ++c) {
    claim.extend(T_volume_initial *
                 claim_initial.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c)));
  }
  return claim;
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

ObjectLifecycle::ObjectLifecycle(cl::Context& ctx, const Config& config,
                                 const core::Intrinsics& intrinsics, map::VoxelPool& pool,
                                 const map::Volume& background,
                                 const track::Preprocessor& camera_preprocessor, em::EStep& estep,
                                 StageTimer& timer, FrameCounters& counters)
    : ctx_(ctx),
      config_(config),
      settings_(deriveObjectSettings(config, intrinsics)),
      intrinsics_(intrinsics),
      pool_(pool),
      background_(background),
      camera_preprocessor_(camera_preprocessor),
      estep_(estep),
      timer_(timer),
      counters_(counters),
      object_preprocessor_(ctx, settings_.preprocess, intrinsics),
      object_tracker_(ctx, settings_.track, intrinsics.width, intrinsics.height),
      reid_tracker_(ctx, settings_.reid_track, intrinsics.width, intrinsics.height),
      raycaster_(ctx, config.map, intrinsics.width, intrinsics.height) {
  config_.objects = settings_.rules;
  const size_t image_bytes = sizeof(float) * static_cast<size_t>(intrinsics.width) *
                             static_cast<size_t>(intrinsics.height);
  fg_mask_ = ctx.buffer(CL_MEM_READ_ONLY, image_bytes);
  new_weights_ = ctx.buffer(CL_MEM_READ_ONLY, image_bytes);
  reid_q_ = ctx.buffer(CL_MEM_READ_ONLY, image_bytes);
}

void ObjectLifecycle::beginFrame(int64_t index, double timestamp) {
  frames_ = index;
  frame_timestamp_ = timestamp;
  pending_fg_.clear();
  estep_ids_.clear();
  unmatched_.clear();
  created_mask_.release();
  deleted_now_.clear();
  confirmed_now_.clear();
}

void ObjectLifecycle::preprocess(const cv::Mat& depth, float frame_max_m) {
  if (!config_.objects.filter_depth) object_preprocessor_.process(depth, frame_max_m);
}

cl_mem ObjectLifecycle::vertexMap() const {
  return config_.objects.filter_depth ? camera_preprocessor_.vertexMap().get()
                                      : object_preprocessor_.vertexMap().get();
}

std::vector<Eigen::Isometry3d> ObjectLifecycle::posesInCamera(
    const Eigen::Isometry3d& T_world_camera, bool predicted) const {
  std::vector<Eigen::Isometry3d> T_oc;
  for (const auto& o : objects_) {
    T_oc.push_back(o.volume->T_world_volume().inverse() * T_world_camera *
                   (predicted ? o.last_motion : Eigen::Isometry3d::Identity()));
  }
  return T_oc;
}

void ObjectLifecycle::setCamera(const Eigen::Isometry3d& T_world_camera,
                                const Eigen::Isometry3d& last_motion) {
  T_world_camera_ = T_world_camera;
  last_motion_ = last_motion;
}

void ObjectLifecycle::markAllLost() {
  for (auto& o : objects_) o.state = ObjectState::kLost;
  estep_ids_.clear();  // the camera's E-step gave the background's weights only: none to show
}

cv::Mat ObjectLifecycle::downloadVertexMap() const {
  cv::Mat vertex(intrinsics_.height, intrinsics_.width, CV_32FC4);
  ctx_.read(config_.objects.filter_depth ? camera_preprocessor_.vertexMap()
                                         : object_preprocessor_.vertexMap(),
            vertex.data, vertex.total() * sizeof(cv::Vec4f));
  return vertex;
}

std::vector<em::EStepVolume> ObjectLifecycle::eStepVolumes(
    const Eigen::Isometry3d& T_world_camera, const std::vector<Eigen::Isometry3d>& T_oc) {
  std::vector<em::EStepVolume> volumes;
  volumes.push_back({deviceView(background_),
                     nullptr,
                     background_.T_world_volume().inverse() * T_world_camera,
                     {},
                     {}});
  estep_ids_ = {0};
  for (size_t k = 0; k < objects_.size(); ++k) {
    TrackedObject& o = objects_[k];
    o.e_step_slot = static_cast<int>(volumes.size());
    volumes.push_back({deviceView(*o.volume), o.volume->countIndex().get(), T_oc[k], {}, {}});
    const map::VolumeDeviceView& view = volumes.back().view;
    Eigen::AlignedBox3d reach(Eigen::Vector3d::Zero(), view.dims_blocks.cast<double>() *
                                                           map::kBlockSize * view.voxel_size_m);
    if (!o.claim_initial.isEmpty()) {
      const Eigen::AlignedBox3d claim = o.claimInVolume();
      volumes.back().claim.lo = claim.min().cast<float>();
      volumes.back().claim.hi = claim.max().cast<float>();
      reach = reach.intersection(claim);
    }
    // Only the pixels whose points can fall in the grid (and claim box) are evaluated.
    volumes.back().pixels = track::boxImageBounds(reach, T_oc[k], intrinsics_).toCv();
    estep_ids_.push_back(o.id);
  }
  return volumes;
}

void ObjectLifecycle::track(const std::vector<Eigen::Isometry3d>& T_oc_predicted,
                            bool residual_everywhere) {
  const cl_mem vertex = vertexMap();
  {
    // E-step again with the tracked camera pose; the objects are those of the first one (same
    // volumes, same predicted poses): their likelihoods are reused.
    ScopedStage s(timer_, "estep");
    estep_.compute(vertex, eStepVolumes(T_world_camera_, T_oc_predicted), residual_everywhere,
                   true);
    ctx_.finish();
  }
  ScopedStage s(timer_, "track_objects");
  for (size_t k = 0; k < objects_.size(); ++k) {
    TrackedObject& o = objects_[k];
    if (o.hidden || o.leaving) {
      // Hidden behind nearer surfaces or leaving the view at the last check: held still in the
      // world (its pose relative to the camera follows the camera), not integrated, not
      // counted as lost.
      o.state = ObjectState::kInvisible;
      o.last_motion = last_motion_;
      if (o.hidden) ++o.hidden_frames;
      logDebug("frame ", frames_, ": object ", o.id, o.hidden ? " hidden" : " leaving the view",
               ": held (", o.hidden_frames, " frames hidden)");
      continue;
    }
    o.hidden_frames = 0;
    const Eigen::Isometry3d T_oc_before =
        o.volume->T_world_volume().inverse() * T_world_camera_ * last_motion_.inverse();
    // q of the object is 0 outside its volume at the E-step's pose (T_oc_predicted): only the
    // pixels its box projects to are evaluated.
    const map::VolumeDeviceView view = deviceView(*o.volume);
    const track::PixelRect roi = track::volumeImageBounds(
        (view.dims_blocks.cast<double>() * map::kBlockSize) * view.voxel_size_m, T_oc_predicted[k],
        intrinsics_);
    // ... and, within that, only the work-groups that meet the pixels with q > 0.
    const cv::Rect claimed = estep_.claimedPixels(o.e_step_slot);
    const track::PixelRect inputs{claimed.x, claimed.y, claimed.x + claimed.width,
                                  claimed.y + claimed.height};
    const track::TrackResult r = object_tracker_.track(view, vertex, estep_.q(o.e_step_slot).get(),
                                                       T_oc_predicted[k], &roi, &inputs);
    counters_.add("object_track_pixels", roi.area());
    counters_.add("object_track_iterations", r.iterations);
    logDebug("frame ", frames_, ": object ", o.id, ": ", r.iterations, " it, valid ",
             r.valid_pixels, "/", r.input_pixels, ", inliers ", r.inlier_ratio, ", motion ",
             r.motion_m, " m ", r.motion_deg, " deg, inverse condition ", r.inverse_condition,
             r.lost ? " LOST " + r.loss_reason : "");
    if (r.lost) {
      // Keep the object where it was in the world (its pose relative to the camera follows
      // the camera); not integrated this frame.
      o.state = ObjectState::kLost;
      ++o.lost_frames;
      o.last_motion = last_motion_;
      o.recent_poses.clear();
      logDebug("frame ", frames_, ": object ", o.id, " not tracked: ", r.loss_reason);
      continue;
    }
    o.state = ObjectState::kTracked;
    o.lost_frames = 0;
    o.last_frame = frames_;
    // The held pose against the tracked one on this frame's pixels (holdStill asks only when
    // the pose rules release a held object): the tracker's last evaluation is the tracked
    // pose's, at the finest stride, and evaluate() compares with it.
    const auto fit_keeps_still = [&](const Eigen::Isometry3d& T_world_held) {
      const track::NormalEquations held = object_tracker_.evaluate(
          view, vertex, estep_.q(o.e_step_slot).get(), T_world_held.inverse() * T_world_camera_,
          object_tracker_.options().pixel_stride, true, &roi, &inputs);
      counters_.add("object_track_iterations", 1);
      const bool keep = em::fitKeepsStill(held.cost_change, held.cost, held.common, r.valid_pixels,
                                          config_.objects);
      logDebug("frame ", frames_, ": object ", o.id, " moves by its poses; the held pose costs ",
               held.cost_change / std::max(held.cost - held.cost_change, 1e-30), " more on ",
               held.common, " of ", r.valid_pixels, " px: ", keep ? "held" : "released");
      return keep;
    };
    if (holdStill(o, T_world_camera_ * r.T_volume_camera.inverse(), fit_keeps_still)) continue;
    o.last_motion = T_oc_before.inverse() * r.T_volume_camera;
    o.volume->setPose(T_world_camera_ * r.T_volume_camera.inverse());
  }
}

bool ObjectLifecycle::holdStill(
    TrackedObject& o, const Eigen::Isometry3d& T_world_tracked,
    const std::function<bool(const Eigen::Isometry3d&)>& fit_keeps_still) {
  const em::ObjectOptions& opt = config_.objects;
  if (opt.still_translation_m <= 0.0) return false;
  // The centre of the region the detections showed (objects.claim_region), else the volume's.
  Eigen::Vector3d centre = o.volume->spec().extentM().cast<double>() / 2.0;
  if (!o.claim_initial.isEmpty()) centre = o.volume->T_volume_initial() * o.claim_initial.center();
  if (o.still) {
    const Eigen::Isometry3d& T_world_held = o.volume->T_world_volume();
    o.held_offsets.push_back(em::poseChange(T_world_held, T_world_tracked, centre));
    if (o.held_offsets.size() > static_cast<size_t>(em::kStartFrames) + 1) {
      o.held_offsets.erase(o.held_offsets.begin());
    }
    if ((em::isStillAt(T_world_held, T_world_tracked, centre, opt) &&
         !em::startsMoving(o.held_offsets, opt)) ||
        fit_keeps_still(T_world_held)) {
      o.last_motion = last_motion_;  // still in the world
      return true;
    }
    o.still = false;
    o.held_offsets.clear();
    o.recent_poses.clear();
    logDebug("frame ", frames_, ": object ", o.id, " moves again");
  }
  o.recent_poses.push_back(T_world_tracked);
  if (static_cast<int>(o.recent_poses.size()) > opt.still_frames) {
    o.recent_poses.erase(o.recent_poses.begin());
  }
  if (em::looksStill(o.recent_poses, centre, opt)) {
    o.still = true;
    o.recent_poses.clear();
    logDebug("frame ", frames_, ": object ", o.id, " still: held");
  }
  return false;
}

const cl::MemHandle* ObjectLifecycle::backgroundWeights() {
  const bool have_q = estep_ids_.size() > 1;  // q of this frame's E-step with the objects
  if (created_mask_.empty()) return have_q ? &estep_.q(0) : nullptr;
  // Objects created this frame: the background does not take their pixels.
  cv::Mat w =
      have_q ? estep_.downloadQ(0) : cv::Mat(intrinsics_.height, intrinsics_.width, CV_32F, 1.0f);
  w = w.mul(1.0f - created_mask_);
  ctx_.write(new_weights_, w.data, w.total() * sizeof(float));
  return &new_weights_;
}

void ObjectLifecycle::integrate(const map::IntegrationInput& in) {
  const bool have_q = estep_ids_.size() > 1;
  for (TrackedObject& o : objects_) {
    if (o.state != ObjectState::kTracked || !have_q || o.first_frame == frames_ ||
        o.reattached_frame == frames_) {
      continue;
    }
    map::IntegrationInput oi = in;
    oi.weights = &estep_.q(o.e_step_slot);
    // Blocks are allocated only near the claim region, by the pixels whose rays cross it: the
    // E-step gives the object no pixel beyond it, so blocks there would never hold its surface
    // (a volume grown by masks spilling onto the wall behind would allocate and integrate the
    // wall's blocks every frame). The margin keeps what the E-step, tracking and ray casts read:
    // the band behind a claimed surface (one truncation) and the trilinear neighbours at the
    // region's border. Without a claim region: the pixels whose rays cross the grid.
    const map::VolumeSpec& spec = o.volume->spec();
    Eigen::AlignedBox3d reach(Eigen::Vector3d::Zero(), spec.dims_blocks.cast<double>() *
                                                           map::kBlockSize * spec.voxel_size_m);
    if (!o.claim_initial.isEmpty()) {
      Eigen::AlignedBox3d claim = o.claimInVolume();
      const Eigen::Vector3d margin =
          Eigen::Vector3d::Constant(spec.truncation_m + map::kBlockSize * spec.voxel_size_m);
      claim.extend(claim.min() - margin);
      claim.extend(claim.max() + margin);
      reach = reach.intersection(claim);
      oi.region = reach;
    }
    oi.pixels = track::boxImageBounds(
                    reach, o.volume->T_world_volume().inverse() * in.T_world_camera, in.intrinsics)
                    .toCv();
    const auto fg = pending_fg_.find(o.id);
    if (fg != pending_fg_.end()) {
      ctx_.write(fg_mask_, fg->second.data, fg->second.total() * sizeof(float));
      oi.fg_mask = &fg_mask_;
    }
    const map::AllocationReport r = o.volume->fuse(oi);
    counters_.add("integrated_blocks", r.listed_blocks);
    if (r.dropped_blocks > 0 && o.pool_full_frames++ % 100 == 0) {
      logWarning("frame ", frames_, ": object ", o.id, ": ", r.dropped_blocks,
                 " blocks found no slot (", o.pool_full_frames,
                 " frame(s) so far; voxel pool full: raise map.memory_mb)");
    }
  }
}

void ObjectLifecycle::createObjects() {
  if (unmatched_.empty()) return;
  const cv::Mat vertex = downloadVertexMap();
  if (!up_world_) {
    const std::optional<Eigen::Vector3d> up = upInCamera(vertex);
    if (up) {
      up_world_ = T_world_camera_.linear() * *up;
      logDebug("frame ", frames_, ": the scene's up (world frame) is ", up_world_->transpose());
    }
  }
  for (const core::Detection& detected : unmatched_) {
    core::Detection d = detected;  // the part of the mask the object is built from
    d.mask = em::creationMask(detected.mask, vertex, config_.objects);
    // A lost or dormant object this detection fits is the same object: re-attach it.
    if (!objects_.empty() || !dormant_.empty()) {
      if (reattach(d, maskedPoints(vertex, d.mask))) continue;
    }
    if (!createObject(d, vertex)) continue;
    if (created_mask_.empty()) created_mask_ = cv::Mat::zeros(d.mask.size(), CV_32F);
    created_mask_ = cv::max(created_mask_, d.mask);
  }
}

void ObjectLifecycle::deleteByExistence() {
  const em::ObjectOptions& opt = config_.objects;
  for (size_t k = objects_.size(); k-- > 0;) {
    if (objects_[k].first_frame == frames_) continue;  // created this frame
    if (objects_[k].existence.shouldDelete(opt)) {
      char reason[96];
      std::snprintf(reason, sizeof(reason), "existence %.3f < %.3f",
                    objects_[k].existence.probability(), opt.existence_delete);
      deleteObject(k, reason);
    }
  }
}

bool ObjectLifecycle::createObject(const core::Detection& d, const cv::Mat& vertex) {
  const em::ObjectOptions& opt = config_.objects;
  if (static_cast<int>(objects_.size()) >= opt.max_objects) {
    logInfo("frame ", frames_, ": no object created for '", d.class_name, "': ", opt.max_objects,
            " objects alive (objects.max_objects)");
    return false;
  }
  std::vector<Eigen::Vector3d> points = maskedPoints(vertex, d.mask);
  for (auto& p : points) p = T_world_camera_ * p;
  const em::VolumePlacement placement = em::placeObject(points, opt);
  if (placement.extent_m <= 0.0) return false;  // fewer than 10 points with depth
  std::vector<em::OrientedBox> existing;
  for (const auto& o : objects_) {
    existing.push_back({o.volume->T_world_volume(), o.volume->spec().extentM().cast<double>()});
  }
  std::string reason;
  if (!em::mayCreate(d, placement, T_world_camera_.translation(), existing, last_ids_, opt,
                     &reason)) {
    logDebug("frame ", frames_, ": no object for '", d.class_name, "': ", reason);
    return false;
  }
  const double centre_depth_m = (T_world_camera_.inverse() * placement.centre_world).z();
  const map::VolumeSpec spec =
      em::objectVolumeSpec(config_.map, opt, placement, centre_depth_m / intrinsics_.fx);
  Eigen::Isometry3d T_world_volume = Eigen::Isometry3d::Identity();
  T_world_volume.translation() =
      placement.centre_world - Eigen::Vector3d::Constant(spec.extentM().x() / 2.0);
  TrackedObject o;
  o.class_name = d.class_name;
  o.rendered = d.class_name != "person";
  o.volume = std::make_unique<map::Volume>(pool_, spec, T_world_volume);
  o.last_motion = last_motion_;  // at first assumed still in the world
  o.first_frame = o.last_frame = frames_;
  // A detector of new things only (motion) never reports its objects again: nothing to confirm.
  o.confirmed = opt.confirm_detections <= 1 || new_objects_only_;
  if (opt.claim_region) {
    // The creation frame is the volume frame now.
    const Eigen::Isometry3d T_volume_world = T_world_volume.inverse();
    std::vector<Eigen::Vector3d> in_volume;
    in_volume.reserve(points.size());
    for (const auto& p : points) in_volume.push_back(T_volume_world * p);
    o.claim_initial =
        em::claimRegion(in_volume, T_volume_world * T_world_camera_.translation(), opt);
  }
  // First integration: weighted by the detection's mask, which also seeds the counts.
  const cv::Mat mask = d.mask.isContinuous() ? d.mask : d.mask.clone();
  ctx_.write(new_weights_, mask.data, mask.total() * sizeof(float));
  ctx_.write(fg_mask_, mask.data, mask.total() * sizeof(float));
  map::IntegrationInput in;
  in.depth = &camera_preprocessor_.inputDepth();
  in.intrinsics = intrinsics_;
  in.T_world_camera = T_world_camera_;
  in.weights = &new_weights_;
  in.fg_mask = &fg_mask_;
  const map::AllocationReport r = o.volume->fuse(in);
  counters_.add("integrated_blocks", r.listed_blocks);
  // A fixed pool: an object that would crowd out the background (or got no slot at all) is not
  // created; its volume and blocks go back to the pool here.
  const map::PoolStats pool = pool_.stats();
  const double free_fraction =
      pool.capacity_slots > 0 ? static_cast<double>(pool.free_slots) / pool.capacity_slots : 0.0;
  if (r.allocated_blocks == 0 || free_fraction < opt.min_free_pool_fraction) {
    if (pool_refused_objects_++ % 20 == 0) {
      char fractions[96];
      std::snprintf(fractions, sizeof(fractions), "%.0f %% of the voxel pool free (below %.0f %%",
                    100.0 * free_fraction, 100.0 * opt.min_free_pool_fraction);
      const std::string why = r.allocated_blocks == 0 ? std::string("the voxel pool is full")
                                                      : std::string("it would leave ") + fractions +
                                                            ", objects.min_free_pool_fraction)";
      logWarning("frame ", frames_, ": no object created for '", d.class_name, "' (",
                 placement.resolution, "^3 voxels, ", r.allocated_blocks, " blocks): ", why, " (",
                 pool_refused_objects_, " refused so far): raise map.memory_mb (",
                 config_.map.memory_mb, " MiB) or lower objects.resolution");
    }
    return false;
  }
  o.id = next_object_id_++;
  logInfo("frame ", frames_, ": object ", o.id, " ('", o.class_name,
          "') created: ", placement.resolution, "^3 voxels of ", placement.voxel_size_m * 100,
          " cm at (", placement.centre_world.transpose(), "), ", r.allocated_blocks, " blocks");
  objects_.push_back(std::move(o));
  return true;
}

void ObjectLifecycle::checkVisibility(const cv::Mat& depth) {
  const em::ObjectOptions& opt = settings_.visibility_rules;  // thresholds at the cast's size
  // Each object is ray-cast alone at objects.visibility_width (q and the depth are brought to
  // that size): its own mask says whether it is in view, and the measured depth in front of it
  // whether it is hidden.
  const bool scaled = settings_.visibility_k.width != intrinsics_.width;
  const std::string at = scaled ? " (ray cast at " + std::to_string(settings_.visibility_k.width) +
                                      "x" + std::to_string(settings_.visibility_k.height) + ")"
                                : std::string();
  // The images live in members: their buffers are reused from frame to frame.
  const cv::Mat* measured = &depth;
  if (scaled) {
    cv::resize(depth, visibility_measured_,
               cv::Size(settings_.visibility_k.width, settings_.visibility_k.height), 0, 0,
               cv::INTER_NEAREST);
    measured = &visibility_measured_;
  }
  for (size_t k = objects_.size(); k-- > 0;) {
    TrackedObject& o = objects_[k];
    // Created or re-attached this frame: its association map is not its own yet.
    if (o.first_frame == frames_ || o.reattached_frame == frames_) continue;
    if (em::lostTooLong(o.lost_frames, opt)) {
      deleteObject(k, "lost: not tracked on " + std::to_string(o.lost_frames) +
                          " frames in a row (> objects.max_lost_frames " +
                          std::to_string(opt.max_lost_frames) + "), its pose is stale");
      continue;
    }
    if (em::hiddenTooLong(o.hidden_frames, opt)) {
      deleteObject(k, "hidden: behind nearer surfaces on " + std::to_string(o.hidden_frames) +
                          " frames in a row (> objects.max_hidden_frames " +
                          std::to_string(opt.max_hidden_frames) + "), its pose is stale");
      continue;
    }
    // Held this frame for leaving the view (not hidden): its visible part is still judged by
    // its association below.
    const bool held_leaving = o.state == ObjectState::kInvisible && o.leaving && !o.hidden;
    raycaster_.render({{o.volume.get(), o.id, 0.0f}}, settings_.visibility_k, T_world_camera_);
    cv::Mat& ids = visibility_ids_;
    raycaster_.download(&visibility_depth_, nullptr, &ids);
    const em::Occlusion occ =
        em::occlusion(visibility_depth_, *measured, o.volume->spec().truncation_m,
                      config_.track.inlier_noise_per_m2, &hidden_mask_);
    // Only an object tracked (or held) up to now becomes hidden or leaving: one whose tracking
    // failed may have moved nearer than its stale pose, which looks the same; it stays lost.
    const bool trusted = o.state == ObjectState::kTracked || o.state == ObjectState::kInvisible;
    const bool held_hidden = o.state == ObjectState::kInvisible && o.hidden;
    o.hidden = em::isHidden(occ, opt, o.hidden) && trusted;
    if (o.hidden && em::movedOn(occ)) {
      // Its part in front shows the scene behind it: the object is not where its pose puts it,
      // so that pose is not held. One held up to now has moved on behind the occluder: lost
      // (tracked from here, else re-identified by a detection). One tracked up to now stays
      // tracked, its part in front judged by its association below.
      logDebug("frame ", frames_, ": object ", o.id, " not hidden: ", occ.seen_through, " of its ",
               occ.rendered - occ.hidden, " px in front see through its surface, it moved on", at);
      o.hidden = false;
      o.hidden_frames = 0;
      if (held_hidden) {
        o.state = ObjectState::kLost;
        ++o.lost_frames;
        o.recent_poses.clear();
      }
    }
    if (o.hidden) {
      logDebug("frame ", frames_, ": object ", o.id, " hidden: ", occ.hidden, " of ", occ.rendered,
               " px behind nearer surfaces, ", occ.seen_through, " seen through", at);
    }
    double in_view = 1.0;
    if (opt.leaving_fraction > 0.0 && em::touchesImageEdge(ids, o.id)) {
      // Only an object cut by the image edge can be leaving: cast it alone over the wide view.
      raycaster_.render({{o.volume.get(), o.id, 0.0f}}, settings_.wide_k, T_world_camera_);
      raycaster_.download(nullptr, nullptr, &wide_ids_);
      in_view = em::inViewFraction(wide_ids_, o.id, settings_.wide_frame);
    }
    o.leaving = em::isLeaving(in_view, opt, o.leaving) && trusted;
    if (o.leaving) {
      logDebug("frame ", frames_, ": object ", o.id, " leaving the view: ", in_view,
               " of its projection inside the image");
    }
    if (em::isInvisible(ids, o.id, opt)) {
      const int visible = em::visiblePixels(ids, o.id, opt);
      deleteObject(k, "invisible: " + std::to_string(visible) + " px < " +
                          std::to_string(opt.invisible_min_px) + " px" + at);
      continue;
    }
    if (o.hidden || (o.state != ObjectState::kTracked && !held_leaving) || estep_ids_.size() <= 1) {
      continue;
    }
    // Mean association over the pixels where the object is in front (hidden ones say nothing).
    ids.setTo(-1, hidden_mask_);
    const double mean_q = visibleMeanAssociation(o, ids);
    if (mean_q < opt.min_mean_association) {
      char reason[96];
      std::snprintf(reason, sizeof(reason), "mean association %.3f < %.3f", mean_q,
                    opt.min_mean_association);
      deleteObject(k, reason + at);
    }
  }
}

double ObjectLifecycle::visibleMeanAssociation(const TrackedObject& o, const cv::Mat& ids) const {
  const cv::Size vis(settings_.visibility_k.width, settings_.visibility_k.height);
  const int s = intrinsics_.width / vis.width;
  if (s * vis.width != intrinsics_.width || s * vis.height != intrinsics_.height) {
    // Not a whole-number scale: INTER_AREA weights depend on the position; the whole image.
    cv::Mat q = estep_.downloadQ(o.e_step_slot);
    cv::resize(q, q, vis, 0, 0, cv::INTER_AREA);
    return em::meanAssociation(q, ids, o.id);
  }
  int r0 = ids.rows, r1 = 0;  // the rows where the object shows
  for (int v = 0; v < ids.rows; ++v) {
    const int* row = ids.ptr<int>(v);
    if (std::find(row, row + ids.cols, o.id) != row + ids.cols) {
      r0 = std::min(r0, v);
      r1 = v + 1;
    }
  }
  if (r0 >= r1) return 0.0;  // as em::meanAssociation without a pixel
  // Rows r0 .. r1 of the visibility image average rows s r0 .. s r1 of the frame's q (a
  // whole-number INTER_AREA: each output pixel from its own s x s block, as in the whole image).
  cv::Mat q = estep_.downloadQRows(o.e_step_slot, r0 * s, (r1 - r0) * s);
  if (s > 1) cv::resize(q, q, cv::Size(vis.width, r1 - r0), 0, 0, cv::INTER_AREA);
  return em::meanAssociation(q, ids.rowRange(r0, r1), o.id);
}

void ObjectLifecycle::confirmIfDue(TrackedObject& o) {
  if (o.confirmed || o.existence.ex < config_.objects.confirm_detections) return;
  o.confirmed = true;
  logInfo("frame ", frames_, ": object ", o.id, " ('", o.class_name, "') confirmed by ",
          o.existence.ex, " detections");
  confirmed_now_.push_back({o.id, o.class_name, std::move(o.earlier)});
  o.earlier.clear();
}

void ObjectLifecycle::deleteObject(size_t i, const std::string& reason) {
  TrackedObject& o = objects_[i];
  if (!o.confirmed) {
    // Never reported: no outcome, no mesh, no dormancy.
    logInfo("frame ", frames_, ": tentative object ", o.id, " ('", o.class_name,
            "') dropped: ", reason);
    object_tracker_.forget(o.volume->key());
    reid_tracker_.forget(o.volume->key());
    objects_.erase(objects_.begin() + static_cast<std::ptrdiff_t>(i));
    return;
  }
  if (config_.objects.reidentify_frames > 0 && o.rendered) {
    // Dormant: the model stays for a detection that fits it (object_reid.cpp).
    logInfo("frame ", frames_, ": object ", o.id, " ('", o.class_name, "') dormant: ", reason);
    o.state = ObjectState::kDormant;
    o.dormant_since = frames_;
    o.dormant_reason = reason;
    o.hidden = o.leaving = false;
    o.hidden_frames = o.lost_frames = 0;
    dormant_.push_back(std::move(o));
    objects_.erase(objects_.begin() + static_cast<std::ptrdiff_t>(i));
    return;
  }
  eraseObject(o, reason);
  objects_.erase(objects_.begin() + static_cast<std::ptrdiff_t>(i));
}

void ObjectLifecycle::eraseObject(TrackedObject& o, const std::string& reason) {
  if (deletion_hook_) deletion_hook_(o);
  object_tracker_.forget(o.volume->key());
  reid_tracker_.forget(o.volume->key());
  ObjectOutcome d;
  d.id = o.id;
  d.class_name = o.class_name;
  d.state = ObjectState::kDeleted;
  d.T_world_object = o.volume->T_world_initial();
  d.T_object_camera = d.T_world_object.inverse() * T_world_camera_;
  d.existence = o.existence.probability();
  d.first_frame = o.first_frame;
  d.last_frame = o.last_frame;
  d.rendered = o.rendered;
  d.deleted_reason = reason;
  deleted_now_.push_back(d);
  logInfo("frame ", frames_, ": object ", o.id, " ('", o.class_name, "') deleted: ", reason);
}

std::vector<ObjectOutcome> ObjectLifecycle::outcomes() const {
  std::vector<ObjectOutcome> out;
  for (const auto* list : {&objects_, &dormant_}) {
    for (const auto& o : *list) {
      if (!o.confirmed) continue;  // tentative: reported once confirmed
      ObjectOutcome r;
      r.id = o.id;
      r.class_name = o.class_name;
      r.state = o.state;
      if (o.state == ObjectState::kDormant) r.deleted_reason = o.dormant_reason;
      r.T_world_object = o.volume->T_world_initial();
      r.T_object_camera = r.T_world_object.inverse() * T_world_camera_;
      r.existence = o.existence.probability();
      r.first_frame = o.first_frame;
      r.last_frame = o.last_frame;
      r.rendered = o.rendered;
      out.push_back(r);
    }
  }
  for (const auto& d : deleted_now_) out.push_back(d);
  std::sort(out.begin(), out.end(),
            [](const ObjectOutcome& a, const ObjectOutcome& b) { return a.id < b.id; });
  return out;
}

void ObjectLifecycle::applyRules(bool detector_ran, const cv::Mat& depth) {
  if (detector_ran) deleteByExistence();
  if (!objects_.empty()) checkVisibility(depth);
  expireDormant();
}

void ObjectLifecycle::keepTentativePoses() {
  for (TrackedObject& o : objects_) {
    if (o.confirmed || o.state != ObjectState::kTracked) continue;
    o.earlier.push_back(
        {frames_, frame_timestamp_, o.volume->T_world_initial().inverse() * T_world_camera_});
  }
}

std::vector<ConfirmedObject> ObjectLifecycle::takeConfirmed() {
  std::vector<ConfirmedObject> confirmed = std::move(confirmed_now_);
  confirmed_now_.clear();
  return confirmed;
}

std::vector<ObjectPose> ObjectLifecycle::poses() const {
  std::vector<ObjectPose> poses;
  for (const auto& o : objects_) poses.push_back({o.id, o.volume->T_world_volume()});
  return poses;
}

const map::Volume* ObjectLifecycle::volume(int id) const {
  for (const auto* list : {&objects_, &dormant_}) {
    for (const auto& o : *list) {
      if (o.id == id) return o.volume.get();
    }
  }
  return nullptr;
}

void ObjectLifecycle::addRenderItems(std::vector<map::RenderItem>* items) const {
  for (const auto& o : objects_) {
    if (!o.rendered) continue;
    map::RenderItem it;
    it.volume = o.volume.get();
    it.id = o.id;
    it.depth_margin_m = static_cast<float>(config_.objects.render_margin_m);
    items->push_back(it);
  }
}

}  // namespace emf::pipeline
