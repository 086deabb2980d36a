// Re-identification of ObjectLifecycle (beyond the paper, which deletes an object and starts over):
// an object retired by a rule stays dormant with its model (objects.reidentify_frames); a
// detection that would create a new object is first fitted to the models of the live objects
// whose pose is stale (lost, or held as hidden or leaving) and of the dormant ones of its class,
// and one that fits re-attaches to that object, which keeps its id and trajectory. A detection
// matched to a lost object is fitted to that object alone (object_matching.cpp).
//
// The fit: the detection's mask is the association map (q = 1 on its pixels) and the object
// tracker aligns the frame's points to the model from several starting poses (T_world_initial
// candidates): the object's last pose, and the last pose turned about the scene's up direction
// (scene_up.h) through the model's centre by 0, 30, .., 330 deg and moved so that the model's
// rendered points have the detection's centroid. A fit that tilts the object more than
// kMaxTiltRad (30 deg) from its last pose (its up no longer up) is refused: objects come back
// turned about the vertical, and a tilted fit is a look-alike face of the model. The best fit (the
// largest inlier share) counts when that share reaches objects.reidentify_min_inliers, at least
// half of the detection's points landed on the model's observed surface and the model's rendered
// mask overlaps the detection (IoU >= kMinMaskIoU). A shape that fits about as well (inlier
// shares within 8 points, with at least 85 % as many of the detection's points on the model's
// observed surface) in orientations more than 20 deg apart (a symmetric box, a car front
// to back) re-attaches only in the one nearest its last pose, and only when that is within 20 deg
// of it.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "common/log.h"
#include "pipeline/object_lifecycle.h"

namespace emf::pipeline {
namespace {

constexpr double kPi = 3.141592653589793;
constexpr int kHeadings = 12;              // starting turns about the up direction, 30 deg apart
constexpr double kMinValidFraction = 0.5;  // of the detection's points on the observed model
constexpr double kMinMaskIoU = 0.3;        // rendered model mask vs detection mask
constexpr float kInside = 0.5f;            // mask threshold
constexpr double kSameFit = 0.08;          // fits whose inlier shares differ by less are alike,
constexpr double kSameSupport = 0.85;      // ... when their points on the model reach this share
constexpr double kAmbiguousRad = 20.0 * kPi / 180.0;  // alike fits further apart: ambiguous
constexpr double kMaxTiltRad = 30.0 * kPi / 180.0;    // fits tilted more: refused
constexpr double kOtherClassReach = 0.5;  // of the model's size: another class's fit moves less

Eigen::Vector3d centroid(const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& p : points) c += p;
  return points.empty() ? c : c / static_cast<double>(points.size());
}

/// The object's centre in its frame at creation: its claim region's, or its volume's.
Eigen::Vector3d modelCentre(const TrackedObject& o) {
  if (!o.claim_initial.isEmpty()) return o.claim_initial.center();
  const map::Volume& v = *o.volume;
  return v.T_volume_initial().inverse() * (v.spec().extentM().cast<double>() / 2.0);
}

}  // namespace

bool ObjectLifecycle::reattach(const core::Detection& d,
                               const std::vector<Eigen::Vector3d>& points_camera,
                               TrackedObject* only) {
  const em::ObjectOptions& opt = config_.objects;
  if (opt.reidentify_frames <= 0 || points_camera.size() < 10) return false;
  const Eigen::Vector3d det_camera = centroid(points_camera);
  const Eigen::Vector3d det_world = T_world_camera_ * det_camera;
  // The detection's extent, to skip models of another size.
  Eigen::AlignedBox3d det_box;
  for (const auto& p : points_camera) det_box.extend(p);
  const double det_size = det_box.sizes().maxCoeff();
  const cv::Mat mask = d.mask.isContinuous() ? d.mask : d.mask.clone();
  ctx_.write(reid_q_, mask.data, mask.total() * sizeof(float));
  const cv::Mat det_binary = mask > kInside;

  struct Candidate {
    TrackedObject* object;
    bool dormant;
  };
  std::vector<Candidate> candidates;
  // Live objects whose pose is stale: lost, or held (hidden, leaving the view) while the object
  // may have moved on. The detector may confuse their class: one of another class re-attaches
  // only near where it was (within kOtherClassReach of its size), not carried off to another
  // object's detection.
  for (auto& o : objects_) {
    if ((o.state == ObjectState::kLost || o.state == ObjectState::kInvisible) && o.rendered &&
        (only == nullptr || only == &o)) {
      candidates.push_back({&o, false});
    }
  }
  // Dormant objects of the detection's class, most recent first, into a free slot only
  // (objects.max_objects).
  if (only == nullptr && static_cast<int>(objects_.size()) < opt.max_objects) {
    for (auto it = dormant_.rbegin(); it != dormant_.rend(); ++it) {
      if (it->class_name == d.class_name) candidates.push_back({&*it, true});
    }
  }

  // Every fit of every candidate; the candidate of the best fit is chosen below.
  struct Fit {
    TrackedObject* object = nullptr;
    bool dormant = false;
    Eigen::Isometry3d T_volume_camera = Eigen::Isometry3d::Identity();
    Eigen::Matrix3d R_world_initial = Eigen::Matrix3d::Identity();  // the fitted orientation
    double score = 0, inliers = 0, iou = 0;
    double on_model = 0;  // share of the detection's points on the model's observed surface
    double turn = 0;      // rotation from the object's last pose, radians
  };
  std::vector<Fit> fits;
  // The world is the first camera's frame (y down) until the scene's up is known.
  const Eigen::Vector3d up = up_world_ ? *up_world_ : Eigen::Vector3d(0.0, -1.0, 0.0);
  for (const Candidate& c : candidates) {
    TrackedObject& o = *c.object;
    map::Volume& volume = *o.volume;
    const double model_size = volume.spec().extentM().maxCoeff() / std::max(1.0, opt.padding);
    if (det_size > 2.5 * model_size || det_size < 0.25 * model_size) continue;
    const Eigen::Isometry3d T_world_volume_before = volume.T_world_volume();
    const Eigen::Isometry3d T_initial_volume = volume.T_volume_initial().inverse();
    const Eigen::Isometry3d T_world_initial = volume.T_world_initial();
    const Eigen::Vector3d centre_initial = modelCentre(o);
    const Eigen::Vector3d centre_world = T_world_initial * centre_initial;
    std::vector<Eigen::Isometry3d> starts;
    starts.push_back(T_world_initial);  // where it was
    for (int k = 0; k < kHeadings; ++k) {
      Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
      turn.linear() = Eigen::AngleAxisd(2 * kPi * k / kHeadings, up).toRotationMatrix();
      turn.translation() = centre_world - turn.linear() * centre_world;
      Eigen::Isometry3d start = turn * T_world_initial;
      start.pretranslate(det_world - centre_world);
      starts.push_back(start);
    }
    const map::VolumeDeviceView view = deviceView(volume);
    for (size_t s = 0; s < starts.size(); ++s) {
      Eigen::Isometry3d start = starts[s];
      if (s > 0) {
        // Move the model so that its rendered points' centroid is the detection's.
        volume.setPose(start * T_initial_volume);
        raycaster_.render({{&volume, o.id, 0.0f}}, settings_.visibility_k, T_world_camera_);
        cv::Mat depth;
        raycaster_.download(&depth, nullptr, nullptr);
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        int n = 0;
        for (int v = 0; v < depth.rows; ++v) {
          const float* z = depth.ptr<float>(v);
          for (int u = 0; u < depth.cols; ++u) {
            if (!(z[u] > 0.0f)) continue;
            sum += Eigen::Vector3d(
                (u - settings_.visibility_k.cx) / settings_.visibility_k.fx * z[u],
                (v - settings_.visibility_k.cy) / settings_.visibility_k.fy * z[u], z[u]);
            ++n;
          }
        }
        if (n < 10) continue;
        start.pretranslate(T_world_camera_.linear() * (det_camera - sum / n));
      }
      const Eigen::Isometry3d T_volume_camera =
          (start * T_initial_volume).inverse() * T_world_camera_;
      const track::PixelRect roi = track::volumeImageBounds(
          (view.dims_blocks.cast<double>() * map::kBlockSize) * view.voxel_size_m, T_volume_camera,
          intrinsics_);
      reid_tracker_.forget(view.volume_key);
      const track::TrackResult r =
          reid_tracker_.track(view, vertexMap(), reid_q_.get(), T_volume_camera, &roi);
      logDebug("frame ", frames_, ": re-identification of object ", o.id, " from start ", s, ": ",
               r.lost ? "lost (" + r.loss_reason + ")" : std::string("fitted"), ", inliers ",
               r.inlier_ratio, ", on the model ", r.valid_fraction);
      if (r.lost || r.valid_fraction < kMinValidFraction) continue;
      const Eigen::Isometry3d T_world_initial_fitted =
          T_world_camera_ * r.T_volume_camera.inverse() * volume.T_volume_initial();
      const Eigen::Matrix3d R_world_fitted = T_world_initial_fitted.linear();
      const Eigen::Vector3d up_fitted = R_world_fitted * T_world_initial.linear().transpose() * up;
      const double moved_m = (T_world_initial_fitted * centre_initial - centre_world).norm();
      if (o.class_name != d.class_name && moved_m > kOtherClassReach * model_size) {
        logDebug("frame ", frames_, ": re-identification of object ", o.id, " ('", o.class_name,
                 "') from start ", s, ": a '", d.class_name, "' detection fits it ", moved_m,
                 " m from where it was, refused");
        continue;
      }
      if (std::acos(std::clamp(up_fitted.dot(up), -1.0, 1.0)) > kMaxTiltRad) {
        logDebug("frame ", frames_, ": re-identification of object ", o.id, " from start ", s,
                 ": fit tilted more than 30 deg from its last pose, refused");
        continue;
      }
      Fit f;
      f.object = &o;
      f.dormant = c.dormant;
      f.T_volume_camera = r.T_volume_camera;
      f.R_world_initial = R_world_fitted;
      f.score = r.inlier_ratio;
      f.inliers = r.inlier_ratio;
      f.on_model = r.valid_fraction;
      f.turn = Eigen::AngleAxisd(T_world_initial.linear().transpose() * f.R_world_initial).angle();
      fits.push_back(f);
    }
    volume.setPose(T_world_volume_before);
  }
  if (fits.empty()) return false;
  const Fit top = *std::max_element(fits.begin(), fits.end(),
                                    [](const Fit& a, const Fit& b) { return a.score < b.score; });
  // A symmetric shape fits as well turned (a box by 90 or 180 deg, a car front to back). When
  // the fits about as good as the best disagree on the orientation, only the one turned least
  // from the last pose may be taken, and only if that turn is small: an orientation guessed
  // among look-alikes would put the rest of the trajectory off.
  Fit best = top;
  bool ambiguous = false;
  for (const Fit& f : fits) {
    if (f.object != top.object || f.score < top.score - kSameFit ||
        f.on_model < kSameSupport * top.on_model) {
      continue;
    }
    if (Eigen::AngleAxisd(f.R_world_initial.transpose() * top.R_world_initial).angle() >
        kAmbiguousRad) {
      ambiguous = true;
    }
    if (f.turn < best.turn) best = f;
  }
  if (ambiguous && best.turn > kAmbiguousRad) {
    logDebug("frame ", frames_, ": detection '", d.class_name, "' fits object ", top.object->id,
             " in several orientations, none near its last one: not re-attached");
    return false;
  }
  if (!best.object || best.inliers < opt.reidentify_min_inliers) return false;
  // The fitted model must cover the detection.
  TrackedObject& o = *best.object;
  const Eigen::Isometry3d T_world_volume_before = o.volume->T_world_volume();
  o.volume->setPose(T_world_camera_ * best.T_volume_camera.inverse());
  raycaster_.render({{o.volume.get(), o.id, 0.0f}}, intrinsics_, T_world_camera_);
  cv::Mat ids;
  raycaster_.download(nullptr, nullptr, &ids);
  best.iou = em::maskIoU(det_binary, ids == o.id);
  if (best.iou < kMinMaskIoU) {
    o.volume->setPose(T_world_volume_before);
    logDebug("frame ", frames_, ": detection '", d.class_name, "' fits object ", o.id, " (inliers ",
             best.inliers, ") but covers it with IoU ", best.iou, " only");
    return false;
  }
  const char* was = best.dormant                    ? " from dormant"
                    : o.state == ObjectState::kLost ? " (was lost)"
                                                    : " (was held)";
  logInfo("frame ", frames_, ": object ", o.id, " ('", o.class_name, "') re-attached", was,
          " to a '", d.class_name, "' detection: inliers ", best.inliers, ", mask IoU ", best.iou);
  o.state = ObjectState::kTracked;
  o.reattached_frame = frames_;
  o.last_frame = frames_;
  o.lost_frames = 0;
  o.hidden = o.leaving = false;
  o.hidden_frames = 0;
  o.last_motion = last_motion_;  // assumed still in the world from here
  o.recent_poses.clear();
  o.still = false;
  if (only == nullptr) {  // a matched detection counts in takeDetection
    o.existence.ex += 1.0;
    confirmIfDue(o);
  }
  o.dormant_since = -1;
  o.dormant_reason.clear();
  object_tracker_.forget(o.volume->key());
  if (best.dormant) {
    const auto it = std::find_if(dormant_.begin(), dormant_.end(),
                                 [&](const TrackedObject& x) { return &x == &o; });
    objects_.push_back(std::move(*it));
    dormant_.erase(it);
  }
  return true;
}

void ObjectLifecycle::expireDormant() {
  const em::ObjectOptions& opt = config_.objects;
  auto erase = [&](size_t i, const std::string& why) {
    eraseObject(dormant_[i], why + " (dormant since frame " +
                                 std::to_string(dormant_[i].dormant_since) +
                                 " after: " + dormant_[i].dormant_reason + ")");
    dormant_.erase(dormant_.begin() + static_cast<std::ptrdiff_t>(i));
  };
  for (size_t i = dormant_.size(); i-- > 0;) {
    if (frames_ - dormant_[i].dormant_since > opt.reidentify_frames) {
      erase(i, "not re-identified within objects.reidentify_frames " +
                   std::to_string(opt.reidentify_frames));
    }
  }
  while (static_cast<int>(dormant_.size()) > opt.max_objects) {
    erase(0, "more than objects.max_objects dormant objects");
  }
  // The pool's room goes to the live volumes first.
  while (!dormant_.empty()) {
    const map::PoolStats pool = pool_.stats();
    const double free_fraction =
        pool.capacity_slots > 0 ? static_cast<double>(pool.free_slots) / pool.capacity_slots : 0.0;
    if (free_fraction >= opt.min_free_pool_fraction) break;
    erase(0, "the voxel pool is short of room (objects.min_free_pool_fraction)");
  }
}

}  // namespace emf::pipeline
