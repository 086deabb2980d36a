#include "em/object_rules.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>

namespace emf::em {

DetectionUse detectionUse(const core::Detection& d, const ObjectOptions& options) {
  if (d.box.width < options.min_detection_px || d.box.height < options.min_detection_px) {
    return DetectionUse::kTooSmall;
  }
  if (d.class_name == "person" && !options.track_person) return DetectionUse::kPersonIgnored;
  return DetectionUse::kUse;
}

bool classMayCreate(const std::string& class_name, const ObjectOptions& options) {
  return std::find(options.exclude_classes.begin(), options.exclude_classes.end(), class_name) ==
         options.exclude_classes.end();
}

double maskIoU(const cv::Mat& a, const cv::Mat& b) {
  CV_Assert(a.size() == b.size());
  cv::Mat ma = a != 0, mb = b != 0;
  const double inter = cv::countNonZero(ma & mb);
  const double uni = cv::countNonZero(ma | mb);
  return uni > 0 ? inter / uni : 0.0;
}

std::vector<int> matchByIoU(const std::vector<std::vector<double>>& iou, double threshold) {
  const size_t rows = iou.size();
  const size_t cols = rows ? iou[0].size() : 0;
  std::vector<int> match(rows, -1);
  std::vector<bool> col_used(cols, false);
  for (;;) {
    double best = -1;
    size_t br = 0, bc = 0;
    for (size_t r = 0; r < rows; ++r) {
      if (match[r] >= 0) continue;
      for (size_t c = 0; c < cols; ++c) {
        if (col_used[c] || iou[r][c] < threshold) continue;
        if (iou[r][c] > best) {
          best = iou[r][c];
          br = r;
          bc = c;
        }
      }
    }
    if (best < 0) break;
    match[br] = static_cast<int>(bc);
    col_used[bc] = true;
  }
  return match;
}

std::vector<int> matchSpilledMasks(const std::vector<cv::Mat>& detections,
                                   const std::vector<std::string>& detection_classes,
                                   const std::vector<int>& match,
                                   const std::vector<MaskObject>& objects, const cv::Mat& ids,
                                   const cv::Mat& depth, const cv::Mat& measured_depth,
                                   double share, double margin_m, double margin_per_m2) {
  CV_Assert(detections.size() == detection_classes.size() && detections.size() == match.size());
  std::vector<int> spilled(detections.size(), -1);
  if (share <= 0.0 || objects.empty()) return spilled;
  CV_Assert(ids.type() == CV_32S && depth.type() == CV_32F && measured_depth.type() == CV_32F &&
            ids.size() == depth.size() && ids.size() == measured_depth.size());
  for (size_t k = 0; k < objects.size(); ++k) {
    if (std::find(match.begin(), match.end(), static_cast<int>(k)) != match.end()) continue;
    const cv::Mat mine = ids == objects[k].id;
    const int pixels = cv::countNonZero(mine);
    if (pixels == 0) continue;
    // Its pixels where the frame's depth shows nothing in front of its ray-cast surface.
    cv::Mat shown = mine.clone();
    for (int v = 0; v < shown.rows; ++v) {
      uint8_t* s = shown.ptr<uint8_t>(v);
      const float* r = depth.ptr<float>(v);
      const float* m = measured_depth.ptr<float>(v);
      for (int u = 0; u < shown.cols; ++u) {
        if (s[u] == 0 || !std::isfinite(r[u]) || !std::isfinite(m[u]) || !(m[u] > 0.0f)) continue;
        const double z = r[u];
        if (m[u] < z - (margin_m + margin_per_m2 * z * z)) s[u] = 0;
      }
    }
    int best = -1;
    double best_share = share;
    for (size_t i = 0; i < detections.size(); ++i) {
      if (match[i] >= 0 || spilled[i] >= 0 || detection_classes[i] != objects[k].class_name) {
        continue;
      }
      CV_Assert(detections[i].size() == ids.size());
      const double held =
          static_cast<double>(cv::countNonZero(shown & (detections[i] != 0))) / pixels;
      if (held >= best_share) {
        best_share = held;
        best = static_cast<int>(i);
      }
    }
    if (best >= 0) spilled[static_cast<size_t>(best)] = static_cast<int>(k);
  }
  return spilled;
}

namespace {
double percentile(std::vector<double> v, double p) {
  // Linear interpolation between closest ranks (numpy's default).
  std::sort(v.begin(), v.end());
  const double pos = p * (v.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (v[hi] - v[lo]) * (pos - lo);
}
}  // namespace

Eigen::AlignedBox3d claimRegion(const std::vector<Eigen::Vector3d>& points,
                                const Eigen::Vector3d& camera, const ObjectOptions& options) {
  Eigen::AlignedBox3d box;  // empty
  if (points.size() < 10) return box;
  Eigen::Vector3d lo, hi, core_lo, core_hi;
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<double> c;
    c.reserve(points.size());
    for (const auto& p : points) c.push_back(p[axis]);
    lo[axis] = percentile(c, 0.02);
    hi[axis] = percentile(c, 0.98);
    core_lo[axis] = percentile(c, 0.1);
    core_hi[axis] = percentile(c, 0.9);
  }
  const double extent = (core_hi - core_lo).maxCoeff();
  const Eigen::Vector3d margin = Eigen::Vector3d::Constant(options.claim_margin * extent);
  box.extend(lo - margin);
  box.extend(hi + margin);
  const Eigen::Vector3d away = 0.5 * (core_lo + core_hi) - camera;
  if (away.norm() > 0) {
    const Eigen::Vector3d shift = away.normalized() * (options.claim_depth * extent);
    box.extend(box.min() + shift);
    box.extend(box.max() + shift);
  }
  return box;
}

VolumePlacement placeObject(const std::vector<Eigen::Vector3d>& points_world,
                            const ObjectOptions& options) {
  VolumePlacement out;
  out.resolution = options.resolution;
  if (points_world.size() < 10) return out;
  double max_extent = 0;
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<double> c;
    c.reserve(points_world.size());
    for (const auto& p : points_world) c.push_back(p[axis]);
    const double lo = percentile(c, 0.1), hi = percentile(c, 0.9);
    out.centre_world[axis] = 0.5 * (lo + hi);
    max_extent = std::max(max_extent, hi - lo);
  }
  out.extent_m = max_extent * options.padding;
  out.voxel_size_m = out.extent_m / options.resolution;
  return out;
}

double boxIoU(const OrientedBox& a, const OrientedBox& b, int n) {
  auto inside = [](const OrientedBox& box, const Eigen::Vector3d& p_world) {
    const Eigen::Vector3d p = box.T_world_box.inverse() * p_world;
    return (p.array() >= 0).all() && (p.array() <= box.size_m.array()).all();
  };
  auto fractionInside = [&](const OrientedBox& from, const OrientedBox& to) {
    int count = 0;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        for (int k = 0; k < n; ++k) {
          const Eigen::Vector3d u((i + 0.5) / n, (j + 0.5) / n, (k + 0.5) / n);
          if (inside(to, from.T_world_box * Eigen::Vector3d(u.cwiseProduct(from.size_m)))) ++count;
        }
    return static_cast<double>(count) / (static_cast<double>(n) * n * n);
  };
  const double va = a.size_m.prod(), vb = b.size_m.prod();
  if (va <= 0 || vb <= 0) return 0;
  // Estimate the intersection from both sides and average (symmetric in a and b).
  const double inter = 0.5 * (fractionInside(a, b) * va + fractionInside(b, a) * vb);
  return inter / (va + vb - inter);
}

double maskCoveredFraction(const cv::Mat& detection_mask, const cv::Mat& object_ids) {
  CV_Assert(detection_mask.size() == object_ids.size());
  cv::Mat m = detection_mask > 0;
  const int total = cv::countNonZero(m);
  if (total == 0) return 0;
  cv::Mat covered = m & (object_ids > 0);
  return static_cast<double>(cv::countNonZero(covered)) / total;
}

bool mayCreate(const core::Detection& d, const VolumePlacement& placement,
               const Eigen::Vector3d& camera_position_world,
               const std::vector<OrientedBox>& existing_volumes, const cv::Mat& object_ids,
               const ObjectOptions& options, std::string* reason) {
  auto fail = [&](const std::string& why) {
    if (reason) *reason = why;
    return false;
  };
  if (!classMayCreate(d.class_name, options)) return fail("class on objects.exclude_classes");
  const int visible = maskVisiblePixels(d.mask, options);
  if (visible < options.invisible_min_px) {
    return fail("only " + std::to_string(visible) +
                " mask px inside the image shrunk by objects.visibility_border_px, below "
                "objects.invisible_min_px " +
                std::to_string(options.invisible_min_px) +
                " (it would be deleted as invisible in the next frame)");
  }
  if (placement.extent_m <= 0) return fail("too few valid depth points in the mask");
  if ((placement.centre_world - camera_position_world).norm() > options.max_create_distance_m) {
    return fail("centre farther than objects.max_create_distance_m");
  }
  OrientedBox candidate;
  candidate.size_m = Eigen::Vector3d::Constant(placement.extent_m);
  candidate.T_world_box.translation() =
      placement.centre_world - Eigen::Vector3d::Constant(0.5 * placement.extent_m);
  for (const auto& v : existing_volumes) {
    if (boxIoU(candidate, v) >= options.max_volume_iou) {
      return fail("volume IoU with an existing volume >= objects.max_volume_iou");
    }
  }
  if (!object_ids.empty() && maskCoveredFraction(d.mask, object_ids) > options.max_mask_covered) {
    return fail("mask already covered by objects beyond objects.max_mask_covered");
  }
  if (reason) reason->clear();
  return true;
}

namespace {
cv::Mat idMask(const cv::Mat& object_ids, int object_id) {
  cv::Mat ids;
  object_ids.convertTo(ids, CV_32S);
  return ids == object_id;
}
}  // namespace

cv::Mat creationMask(const cv::Mat& mask, const cv::Mat& vertex, const ObjectOptions& options) {
  CV_Assert(mask.type() == CV_32F && vertex.type() == CV_32FC4 && mask.size() == vertex.size());
  if (options.creation_depth_jump_m <= 0.0) return mask.clone();
  // Pixels of the mask with valid depth and no depth jump to any valid 4-neighbour.
  cv::Mat smooth(mask.size(), CV_8U, cv::Scalar(0));
  const int du[4] = {1, -1, 0, 0};
  const int dv[4] = {0, 0, 1, -1};
  // A mask pixel with valid depth: its depth and the largest depth step to a neighbour that
  // still counts as the same surface.
  const auto maskDepth = [&](int u, int v, double& z, double& jump) {
    if (!(mask.at<float>(v, u) > 0.5f)) return false;
    const cv::Vec4f& p = vertex.at<cv::Vec4f>(v, u);
    if (p[3] == 0.0f) return false;
    z = p[2];
    jump = options.creation_depth_jump_m + options.creation_depth_jump_per_m2 * z * z;
    return true;
  };
  for (int v = 0; v < mask.rows; ++v) {
    for (int u = 0; u < mask.cols; ++u) {
      double z = 0.0, jump = 0.0;
      if (!maskDepth(u, v, z, jump)) continue;
      bool continuous = true;
      for (int k = 0; k < 4 && continuous; ++k) {
        const int uu = u + du[k], vv = v + dv[k];
        if (uu < 0 || vv < 0 || uu >= mask.cols || vv >= mask.rows) continue;
        const cv::Vec4f& q = vertex.at<cv::Vec4f>(vv, uu);
        if (q[3] != 0.0f && std::abs(static_cast<double>(q[2]) - z) > jump) continuous = false;
      }
      if (continuous) smooth.at<uint8_t>(v, u) = 255;
    }
  }
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(smooth, labels, stats, centroids, 4, CV_32S);
  int largest = 0;
  for (int i = 1; i < n; ++i) {
    if (largest == 0 ||
        stats.at<int>(i, cv::CC_STAT_AREA) > stats.at<int>(largest, cv::CC_STAT_AREA)) {
      largest = i;
    }
  }
  cv::Mat out = cv::Mat::zeros(mask.size(), CV_32F);
  if (largest == 0) return out;
  // The region plus the mask pixels next to it without a jump to their neighbour in it: the
  // object's own silhouette pixels, which have a jump to the surface behind only.
  for (int v = 0; v < mask.rows; ++v) {
    for (int u = 0; u < mask.cols; ++u) {
      if (labels.at<int>(v, u) == largest) {
        out.at<float>(v, u) = mask.at<float>(v, u);
        continue;
      }
      double z = 0.0, jump = 0.0;
      if (!maskDepth(u, v, z, jump)) continue;
      for (int k = 0; k < 4; ++k) {
        const int uu = u + du[k], vv = v + dv[k];
        if (uu < 0 || vv < 0 || uu >= mask.cols || vv >= mask.rows) continue;
        if (labels.at<int>(vv, uu) != largest) continue;
        if (std::abs(static_cast<double>(vertex.at<cv::Vec4f>(vv, uu)[2]) - z) <= jump) {
          out.at<float>(v, u) = mask.at<float>(v, u);
          break;
        }
      }
    }
  }
  return out;
}

double objectTruncation(const ObjectOptions& options, double map_truncation_voxels,
                        double voxel_size_m, double pixel_footprint_m) {
  const double wanted = std::max(options.truncation_voxels * voxel_size_m,
                                 options.truncation_min_px * pixel_footprint_m);
  return std::min(wanted, map_truncation_voxels * voxel_size_m);
}

map::VolumeSpec objectVolumeSpec(const map::MapOptions& map_options, const ObjectOptions& options,
                                 const VolumePlacement& placement, double pixel_footprint_m) {
  map::VolumeSpec spec = map::VolumeSpec::object(map_options, placement.resolution,
                                                 static_cast<float>(placement.voxel_size_m));
  spec.free_space_full_weight = options.free_space_full_weight;
  spec.behind_dropoff = options.behind_dropoff;
  spec.max_weight = static_cast<float>(options.max_weight);
  spec.truncation_m = static_cast<float>(objectTruncation(
      options, map_options.truncation_voxels, placement.voxel_size_m, pixel_footprint_m));
  return spec;
}

int maskVisiblePixels(const cv::Mat& mask, const ObjectOptions& options) {
  const int b = options.visibility_border_px;
  if (mask.empty() || mask.cols <= 2 * b || mask.rows <= 2 * b) return 0;
  const cv::Rect inner(b, b, mask.cols - 2 * b, mask.rows - 2 * b);
  cv::Mat m;
  mask(inner).convertTo(m, CV_32F);
  return cv::countNonZero(m > 0.5f);
}

int visiblePixels(const cv::Mat& object_ids, int object_id, const ObjectOptions& options) {
  const int b = options.visibility_border_px;
  if (object_ids.cols <= 2 * b || object_ids.rows <= 2 * b) return 0;
  const cv::Rect inner(b, b, object_ids.cols - 2 * b, object_ids.rows - 2 * b);
  return cv::countNonZero(idMask(object_ids(inner), object_id));
}

bool isInvisible(const cv::Mat& object_ids, int object_id, const ObjectOptions& options) {
  const int inside = visiblePixels(object_ids, object_id, options);
  if (inside >= options.invisible_min_px) return false;
  if (options.invisible_inside_fraction <= 0.0 || inside == 0) return true;
  const int rendered = cv::countNonZero(idMask(object_ids, object_id));
  return inside < options.invisible_inside_fraction * rendered;
}

double meanAssociation(const cv::Mat& q, const cv::Mat& object_ids, int object_id) {
  CV_Assert(q.type() == CV_32F && q.size() == object_ids.size());
  const cv::Mat m = idMask(object_ids, object_id);
  const int n = cv::countNonZero(m);
  if (n == 0) return 0;
  cv::Mat weights;
  m.convertTo(weights, CV_32F, 1.0 / 255.0);
  return cv::sum(q.mul(weights))[0] / n;
}

Occlusion occlusion(const cv::Mat& rendered_depth, const cv::Mat& measured_depth, double margin_m,
                    double margin_per_m2, cv::Mat* hidden_mask) {
  CV_Assert(rendered_depth.type() == CV_32F && measured_depth.type() == CV_32F &&
            rendered_depth.size() == measured_depth.size());
  Occlusion occ;
  if (hidden_mask) hidden_mask->create(rendered_depth.size(), CV_8U);
  for (int v = 0; v < rendered_depth.rows; ++v) {
    const float* r = rendered_depth.ptr<float>(v);
    const float* m = measured_depth.ptr<float>(v);
    uint8_t* h = hidden_mask ? hidden_mask->ptr<uint8_t>(v) : nullptr;
    for (int u = 0; u < rendered_depth.cols; ++u) {
      bool hidden = false;
      if (std::isfinite(r[u]) && r[u] > 0.0f) {
        ++occ.rendered;
        const double z = r[u];
        const bool measured = std::isfinite(m[u]) && m[u] > 0.0f;
        const double margin = margin_m + margin_per_m2 * z * z;
        hidden = measured && m[u] < z - margin;
        if (hidden) ++occ.hidden;
        if (measured && m[u] > z + margin) ++occ.seen_through;
      }
      if (h) h[u] = hidden ? 255 : 0;
    }
  }
  return occ;
}

int uncoverStaleBackground(cv::Mat* ids, const cv::Mat& depth, const cv::Mat& object_ids,
                           const cv::Mat& object_depth, const cv::Mat& measured_depth,
                           double margin_m, double margin_per_m2) {
  CV_Assert(ids != nullptr && ids->type() == CV_32S && object_ids.type() == CV_32S &&
            depth.type() == CV_32F && object_depth.type() == CV_32F &&
            measured_depth.type() == CV_32F && ids->size() == depth.size() &&
            ids->size() == object_ids.size() && ids->size() == object_depth.size() &&
            ids->size() == measured_depth.size());
  int uncovered = 0;
  for (int v = 0; v < ids->rows; ++v) {
    int* id = ids->ptr<int>(v);
    const float* bg = depth.ptr<float>(v);
    const int* oid = object_ids.ptr<int>(v);
    const float* oz = object_depth.ptr<float>(v);
    const float* m = measured_depth.ptr<float>(v);
    for (int u = 0; u < ids->cols; ++u) {
      if (id[u] != 0 || oid[u] <= 0 || !std::isfinite(m[u]) || !(m[u] > 0.0f) ||
          !std::isfinite(bg[u]) || !std::isfinite(oz[u])) {
        continue;
      }
      const double z = m[u];
      const double margin = margin_m + margin_per_m2 * z * z;
      if (z > bg[u] + margin && std::abs(z - oz[u]) <= margin) {
        id[u] = oid[u];
        ++uncovered;
      }
    }
  }
  return uncovered;
}

bool isHidden(const Occlusion& occlusion, const ObjectOptions& options, bool was_hidden) {
  if (options.hidden_fraction <= 0.0 || occlusion.rendered == 0) return false;
  const double threshold = was_hidden
                               ? std::min(options.visible_again_fraction, options.hidden_fraction)
                               : options.hidden_fraction;
  return occlusion.hiddenFraction() >= threshold;
}

bool movedOn(const Occlusion& occlusion) {
  const int unhidden = occlusion.rendered - occlusion.hidden;
  return occlusion.seen_through > 0 && 2 * occlusion.seen_through >= unhidden &&
         10 * occlusion.seen_through >= occlusion.rendered;
}

double inViewFraction(const cv::Mat& wide_ids, int object_id, const cv::Rect& frame) {
  CV_Assert(wide_ids.type() == CV_32S &&
            (frame & cv::Rect(0, 0, wide_ids.cols, wide_ids.rows)) == frame);
  const int all = cv::countNonZero(idMask(wide_ids, object_id));
  if (all == 0) return 1.0;
  return static_cast<double>(cv::countNonZero(idMask(wide_ids(frame), object_id))) / all;
}

bool touchesImageEdge(const cv::Mat& object_ids, int object_id) {
  const int w = object_ids.cols, h = object_ids.rows;
  if (w == 0 || h == 0) return false;
  for (const cv::Rect& edge : {cv::Rect(0, 0, w, 1), cv::Rect(0, h - 1, w, 1), cv::Rect(0, 0, 1, h),
                               cv::Rect(w - 1, 0, 1, h)}) {
    if (cv::countNonZero(idMask(object_ids(edge), object_id)) > 0) return true;
  }
  return false;
}

bool isLeaving(double in_view_fraction, const ObjectOptions& options, bool was_leaving) {
  if (options.leaving_fraction <= 0.0) return false;
  const double threshold = was_leaving
                               ? std::max(options.in_view_again_fraction, options.leaving_fraction)
                               : options.leaving_fraction;
  return in_view_fraction < threshold;
}

bool hiddenTooLong(int consecutive_hidden_frames, const ObjectOptions& options) {
  return options.max_hidden_frames > 0 && consecutive_hidden_frames > options.max_hidden_frames;
}

bool lostTooLong(int consecutive_lost_frames, const ObjectOptions& options) {
  return options.max_lost_frames > 0 && consecutive_lost_frames > options.max_lost_frames;
}

PoseChange poseChange(const Eigen::Isometry3d& T_world_a, const Eigen::Isometry3d& T_world_b,
                      const Eigen::Vector3d& centre) {
  const Eigen::Isometry3d T_b_a = T_world_b.inverse() * T_world_a;  // volume frame a -> b
  PoseChange c;
  c.centre_m = (T_b_a * centre - centre).norm();
  c.angle_deg = Eigen::AngleAxisd(T_b_a.linear()).angle() * 180.0 / M_PI;
  return c;
}

bool isStillAt(const Eigen::Isometry3d& T_world_held, const Eigen::Isometry3d& T_world_tracked,
               const Eigen::Vector3d& centre, const ObjectOptions& options) {
  const PoseChange c = poseChange(T_world_held, T_world_tracked, centre);
  return c.centre_m <= options.still_translation_m && c.angle_deg <= options.still_rotation_deg;
}

bool fitKeepsStill(double cost_change, double held_cost, int common, int valid,
                   const ObjectOptions& options) {
  if (options.still_release_cost <= 0.0 || valid <= 0 || 2 * common < valid) return false;
  const double tracked_cost = held_cost - cost_change;
  if (!(tracked_cost > 0.0)) return false;
  return cost_change < options.still_release_cost * tracked_cost;
}

bool startsMoving(const std::vector<PoseChange>& offsets, const ObjectOptions& options) {
  const size_t n = offsets.size();
  if (options.still_translation_m <= 0.0 || n < static_cast<size_t>(kStartFrames) + 1) {
    return false;
  }
  bool moves = true, turns = true;
  for (size_t i = n - kStartFrames; i < n; ++i) {
    moves = moves && offsets[i].centre_m > offsets[i - 1].centre_m;
    turns = turns && offsets[i].angle_deg > offsets[i - 1].angle_deg;
  }
  return (moves && offsets.back().centre_m >= 0.25 * options.still_translation_m) ||
         (turns && offsets.back().angle_deg >= 0.5 * options.still_rotation_deg);
}

bool looksStill(const std::vector<Eigen::Isometry3d>& window, const Eigen::Vector3d& centre,
                const ObjectOptions& options) {
  if (options.still_translation_m <= 0.0 || options.still_frames < 2 ||
      static_cast<int>(window.size()) < options.still_frames) {
    return false;
  }
  for (const auto& T : window) {
    if (!isStillAt(window.back(), T, centre, options)) return false;
  }
  return true;
}

GrowPlan planGrowth(const std::vector<Eigen::Vector3d>& points_volume,
                    const Eigen::Vector3i& dims_blocks, double voxel_size_m, int block_voxels,
                    int max_blocks_per_side) {
  GrowPlan plan;
  const double block_m = voxel_size_m * block_voxels;
  for (const auto& p : points_volume) {
    for (int a = 0; a < 3; ++a) {
      const double hi_m = dims_blocks[a] * block_m;
      if (p[a] < 0) {
        plan.add_low[a] = std::max(plan.add_low[a], static_cast<int>(std::ceil(-p[a] / block_m)));
      } else if (p[a] >= hi_m) {
        plan.add_high[a] =
            std::max(plan.add_high[a], static_cast<int>(std::floor((p[a] - hi_m) / block_m)) + 1);
      }
    }
  }
  plan.add_low = plan.add_low.cwiseMin(max_blocks_per_side);
  plan.add_high = plan.add_high.cwiseMin(max_blocks_per_side);
  return plan;
}

}  // namespace emf::em
