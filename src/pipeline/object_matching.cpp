// A detection frame's matching (docs/method.md#detections): which detections are usable, the
// objects' masks ray-cast at the detection's frame, the IoU match, and what a matched or a
// missed object takes from it (existence counts, foreground masks, claim region, growth).

#include <algorithm>
#include <string>

#include "common/log.h"
#include "pipeline/object_lifecycle.h"
#include "pipeline/object_points.h"

namespace emf::pipeline {

namespace {

// A tentative object (objects.confirm_detections) missed by this many detection frames is
// dropped: a false detection is seldom repeated, a real object seldom missed twice in a row.
constexpr double kTentativeMisses = 2.0;

cv::Mat binaryMask(const cv::Mat& probability) { return probability > kMaskInside; }

/// Depth (m) of the vertex map's points along the optical axis, NaN where there is none.
cv::Mat measuredDepth(const cv::Mat& vertex) {
  cv::Mat depth(vertex.size(), CV_32F);
  for (int v = 0; v < vertex.rows; ++v) {
    const cv::Vec4f* p = vertex.ptr<cv::Vec4f>(v);
    float* z = depth.ptr<float>(v);
    for (int u = 0; u < vertex.cols; ++u) z[u] = p[u][3] > 0.0f ? p[u][2] : NAN;
  }
  return depth;
}

}  // namespace

int ObjectLifecycle::matchDetections(const DetectionBatch& batch,
                                     std::vector<DetectionMatch>* matches) {
  const std::vector<const core::Detection*> usable = usableDetections(batch.detections);
  new_objects_only_ = batch.new_objects_only;
  cv::Mat vertex;  // the frame's vertex map, downloaded once when needed
  renderObjectIds(batch, &vertex);
  const std::vector<int> match = matchByMasks(usable, matches);
  std::vector<bool> matched(objects_.size(), false);
  // A mask spilled over an object that no detection matched shows that object (not for a late
  // result: the frame's depth is not the one its mask was cut from). It gives foreground counts
  // on the object's own ray-cast pixels only, and no growth or claim region: its pixels around
  // the object would count as the object's.
  std::vector<int> spilled(usable.size(), -1);
  if (config_.objects.match_spilled > 0.0 && batch.frames_late == 0 && !objects_.empty()) {
    if (vertex.empty()) vertex = downloadVertexMap();
    std::vector<cv::Mat> masks;
    std::vector<std::string> classes;
    for (const core::Detection* d : usable) {
      masks.push_back(binaryMask(d->mask));
      classes.push_back(d->class_name);
    }
    std::vector<em::MaskObject> shown;
    for (const auto& o : objects_) shown.push_back({o.id, o.class_name});
    spilled =
        em::matchSpilledMasks(masks, classes, match, shown, last_ids_, last_depth_,
                              measuredDepth(vertex), config_.objects.match_spilled,
                              config_.objects.render_margin_m, config_.track.inlier_noise_per_m2);
  }
  for (size_t i = 0; i < usable.size(); ++i) {
    if (spilled[i] >= 0) {
      TrackedObject& o = objects_[static_cast<size_t>(spilled[i])];
      matched[static_cast<size_t>(spilled[i])] = true;
      (*matches)[matches->size() - usable.size() + i].object_id = o.id;
      logDebug("frame ", frames_, ": detection '", usable[i]->class_name, "' spills over object ",
               o.id, " (objects.match_spilled ", config_.objects.match_spilled, ")");
      o.existence.ex += 1.0;
      confirmIfDue(o);
      // Foreground counts only where the mask covers the object's own ray-cast pixels.
      cv::Mat fg = usable[i]->mask.clone();
      fg.setTo(NAN, last_ids_ != o.id);
      pending_fg_[o.id] = fg;
      continue;
    }
    if (match[i] < 0) {
      unmatched_.push_back(*usable[i]);
      continue;
    }
    matched[static_cast<size_t>(match[i])] = true;
    TrackedObject& o = objects_[static_cast<size_t>(match[i])];
    // Lost, the object's pose is stale, yet the detection shows it, maybe moved on from there:
    // it is fitted to the detection as a re-identification would (not for a late result, whose
    // mask belongs to an earlier frame). A held object is not: hidden, its visible part may be
    // too little to fit (em::movedOn turns one that moved on into a lost one).
    if (o.state == ObjectState::kLost && batch.frames_late == 0) {
      if (vertex.empty()) vertex = downloadVertexMap();
      core::Detection shown = *usable[i];
      shown.mask = em::creationMask(usable[i]->mask, vertex, config_.objects);
      reattach(shown, maskedPoints(vertex, shown.mask), &o);
    }
    takeDetection(o, *usable[i], &vertex);
  }
  // A detector of new things only (motion) is silent about the objects it already created.
  if (!batch.new_objects_only) countMisses(matched);
  return static_cast<int>(usable.size());
}

std::vector<const core::Detection*> ObjectLifecycle::usableDetections(
    const std::vector<core::Detection>& detections) const {
  std::vector<const core::Detection*> usable;
  for (const auto& d : detections) {
    if (d.mask.size() != cv::Size(intrinsics_.width, intrinsics_.height) ||
        d.mask.type() != CV_32F) {
      logWarning("frame ", frames_, ": detection '", d.class_name,
                 "' ignored: its mask is not a CV_32F image of the frame size");
      continue;
    }
    const em::DetectionUse use = em::detectionUse(d, config_.objects);
    if (use == em::DetectionUse::kUse) {
      usable.push_back(&d);
    } else if (use == em::DetectionUse::kTooSmall) {
      logDebug("frame ", frames_, ": detection '", d.class_name, "' dropped: its box (",
               d.box.width, "x", d.box.height, " px) has a side below objects.min_detection_px ",
               config_.objects.min_detection_px, " (at this image size)");
    }
  }
  return usable;
}

void ObjectLifecycle::renderObjectIds(const DetectionBatch& batch, cv::Mat* vertex) {
  // Ray-cast object masks (the background occludes) at the poses of the frame the detector ran
  // on: the current ones, or for a late (async) result the poses it carries; objects created
  // after that frame are not matched.
  const em::ObjectOptions& opt = config_.objects;
  last_ids_ = cv::Mat(intrinsics_.height, intrinsics_.width, CV_32S, cv::Scalar(-1));
  if (objects_.empty()) return;
  const bool late = batch.frames_late > 0;
  std::vector<Eigen::Isometry3d> current_poses;
  std::vector<map::RenderItem> items;
  items.push_back({&background_, 0, 0.0f});
  for (auto& o : objects_) {
    current_poses.push_back(o.volume->T_world_volume());
    if (late) {
      const auto it = std::find_if(batch.objects.begin(), batch.objects.end(),
                                   [&](const ObjectPose& p) { return p.id == o.id; });
      if (it == batch.objects.end()) continue;
      o.volume->setPose(it->T_world_object);
    }
    items.push_back({o.volume.get(), o.id, static_cast<float>(opt.render_margin_m)});
  }
  // The frame's depth shows where the background's surface is stale (only for the frame the
  // detector ran on: a late result's frame is gone).
  const bool measured = opt.mask_measured_depth && !late;
  cv::Mat object_depth, object_ids;
  if (measured && items.size() > 1) {
    raycaster_.render(std::vector<map::RenderItem>(items.begin() + 1, items.end()), intrinsics_,
                      batch.T_world_camera);
    raycaster_.download(&object_depth, nullptr, &object_ids);
  }
  raycaster_.render(items, intrinsics_, batch.T_world_camera);
  cv::Mat& depth = last_depth_;
  raycaster_.download(&depth, nullptr, &last_ids_);
  if (!object_ids.empty()) {
    if (vertex->empty()) *vertex = downloadVertexMap();
    const int uncovered = em::uncoverStaleBackground(&last_ids_, depth, object_ids, object_depth,
                                                     measuredDepth(*vertex), opt.render_margin_m,
                                                     config_.track.inlier_noise_per_m2);
    if (uncovered > 0) {
      logDebug("frame ", frames_, ": ", uncovered,
               " mask pixels where the depth sees through the background onto an object");
    }
  }
  for (size_t k = 0; k < objects_.size(); ++k) objects_[k].volume->setPose(current_poses[k]);
}

std::vector<int> ObjectLifecycle::matchByMasks(const std::vector<const core::Detection*>& usable,
                                               std::vector<DetectionMatch>* matches) const {
  std::vector<std::vector<double>> iou(usable.size(), std::vector<double>(objects_.size(), 0.0));
  std::vector<cv::Mat> object_masks;
  for (const auto& o : objects_) object_masks.push_back(last_ids_ == o.id);
  for (size_t i = 0; i < usable.size(); ++i) {
    const cv::Mat det = binaryMask(usable[i]->mask);
    for (size_t k = 0; k < objects_.size(); ++k) iou[i][k] = em::maskIoU(det, object_masks[k]);
  }
  const std::vector<int> match = em::matchByIoU(iou, config_.objects.match_iou);
  for (size_t i = 0; i < usable.size(); ++i) {
    DetectionMatch m;
    m.class_name = usable[i]->class_name;
    if (match[i] >= 0) m.object_id = objects_[static_cast<size_t>(match[i])].id;
    for (size_t k = 0; k < objects_.size(); ++k) {
      if (iou[i][k] > m.best_iou) {
        m.best_iou = iou[i][k];
        m.best_object = objects_[k].id;
      }
    }
    matches->push_back(m);
  }
  return match;
}

void ObjectLifecycle::takeDetection(TrackedObject& o, const core::Detection& d, cv::Mat* vertex) {
  const em::ObjectOptions& opt = config_.objects;
  o.existence.ex += 1.0;
  confirmIfDue(o);
  // Foreground counts from the detection where no other object is in front.
  cv::Mat fg = d.mask.clone();
  const cv::Mat other = (last_ids_ > 0) & (last_ids_ != o.id);
  fg.setTo(NAN, other);
  pending_fg_[o.id] = fg;
  // Growth: the detection's robust extent (10th-90th percentile, padded as at creation)
  // must fit in the volume.
  if (vertex->empty()) *vertex = downloadVertexMap();
  std::vector<Eigen::Vector3d> pts = maskedPoints(*vertex, d.mask);
  if (pts.size() < 10) return;
  const Eigen::Isometry3d T_volume_camera = o.volume->T_world_volume().inverse() * T_world_camera_;
  for (auto& p : pts) p = T_volume_camera * p;
  // The claim region grows by what this detection shows of the object: its largest
  // depth-continuous part, as at creation (a mask spilling onto the wall behind would stretch
  // the region to the wall). Kept in the creation frame.
  if (opt.claim_region) {
    std::vector<Eigen::Vector3d> shown_pts =
        maskedPoints(*vertex, em::creationMask(d.mask, *vertex, opt));
    for (auto& p : shown_pts) p = T_volume_camera * p;
    const Eigen::AlignedBox3d shown =
        em::claimRegion(shown_pts, T_volume_camera.translation(), opt);
    const Eigen::Isometry3d T_initial_volume = o.volume->T_volume_initial().inverse();
    for (int c = 0; c < 8; ++c) {
      o.claim_initial.extend(T_initial_volume *
                             shown.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c)));
    }
  }
  if (opt.max_grow_blocks == 0) return;
  const Eigen::Vector3d lo = percentile(pts, 0.1), hi = percentile(pts, 0.9);
  const Eigen::Vector3d pad = (hi - lo) * (opt.padding - 1.0) / 2.0;
  const map::VolumeSpec& spec = o.volume->spec();
  const em::GrowPlan plan = em::planGrowth({lo - pad, hi + pad}, spec.dims_blocks,
                                           spec.voxel_size_m, map::kBlockSize, opt.max_grow_blocks);
  if (plan.any()) {
    o.volume->grow(plan.add_low, plan.add_high);
    logInfo("frame ", frames_, ": object ", o.id, " grown to ",
            o.volume->spec().dims_blocks.transpose() * map::kBlockSize, " voxels");
  }
}

void ObjectLifecycle::countMisses(const std::vector<bool>& matched) {
  for (size_t k = 0; k < objects_.size(); ++k) {
    if (!matched[k]) objects_[k].existence.non_ex += 1.0;
  }
  // A tentative object missed twice before its confirmation was not there: gone unreported.
  for (size_t k = objects_.size(); k-- > 0;) {
    TrackedObject& o = objects_[k];
    if (!o.confirmed && o.existence.non_ex >= kTentativeMisses) {
      deleteObject(k, "not confirmed (objects.confirm_detections " +
                          std::to_string(config_.objects.confirm_detections) + "): missed by " +
                          std::to_string(kTentativeMisses) + " detection frames");
    }
  }
}

}  // namespace emf::pipeline
