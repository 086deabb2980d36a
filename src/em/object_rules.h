// The object lifecycle rules of docs/method.md#detection-frames and #visibility-and-deletion as
// pure functions on masks, boxes and point sets, so each rule is testable on a constructed case.
// The pipeline (src/pipeline/) applies them with the ray-cast object masks and the association maps
// of the current frame.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/frame.h"
#include "em/em_options.h"
#include "map/map_options.h"
#include "map/volume.h"

namespace emf::em {

/// Why a detection is not used.
enum class DetectionUse { kUse, kTooSmall, kPersonIgnored };

/// Step 5, first bullet: detections whose box is narrower or lower than min_detection_px are
/// dropped; "person" is dropped unless objects.track_person. (Excluded classes are kept here:
/// they may still match existing objects but never create one, see mayCreate().)
DetectionUse detectionUse(const core::Detection& d, const ObjectOptions& options);

/// True if the class may create a new object (not on objects.exclude_classes).
bool classMayCreate(const std::string& class_name, const ObjectOptions& options);

/// IoU of two masks (non-zero = inside). Same size required. 0 when both are empty.
double maskIoU(const cv::Mat& a, const cv::Mat& b);

/// Greedy one-to-one association of detections (rows) to objects (columns) by IoU: repeatedly
/// take the largest remaining IoU >= threshold. Returns, per detection, the column or -1.
std::vector<int> matchByIoU(const std::vector<std::vector<double>>& iou, double threshold);

/// An object as the spilled-mask rule sees it: its id in the ray-cast ids and its class.
struct MaskObject {
  int id = 0;
  std::string class_name;
};

/// Masks spilled over objects (objects.match_spilled = `share`, beyond the paper). A detector's
/// mask that spills over an object onto what surrounds it overlaps the object's ray-cast mask
/// with a low IoU only because it is large; left unmatched, it would make a second object of the
/// first. Among the detections matchByIoU left (match[i] < 0), one of an object's class holding
/// at least `share` of that object's pixels in `ids` is taken as a spilled mask of it, when no
/// detection matched the object. A pixel counts as held where the detection covers it and the
/// measured depth is not nearer than `depth` (the ray cast) by more than margin_m +
/// margin_per_m2 z^2: a new object of the class in front of an old one is no spill over it.
/// Each object takes the detection holding the largest share of it, one to one, objects in
/// order. `detections`: binary masks (non-zero = inside); `ids` CV_32S, `depth` and
/// `measured_depth` CV_32F (NaN = none), all of one size. Returns, per detection, the index of
/// its object in `objects` or -1 (share = 0: all -1).
std::vector<int> matchSpilledMasks(const std::vector<cv::Mat>& detections,
                                   const std::vector<std::string>& detection_classes,
                                   const std::vector<int>& match,
                                   const std::vector<MaskObject>& objects, const cv::Mat& ids,
                                   const cv::Mat& depth, const cv::Mat& measured_depth,
                                   double share, double margin_m, double margin_per_m2);

/// Existence counts of an object (step 5): Ex counts matched detection frames, NonEx unmatched.
struct Existence {
  double ex = 1.0;  // the creating detection counts once
  double non_ex = 0.0;
  double probability() const { return ex / (ex + non_ex); }
  /// True when the object must be deleted (probability below objects.existence_delete).
  bool shouldDelete(const ObjectOptions& o) const { return probability() < o.existence_delete; }
};

/// An axis-aligned cube of voxels placed in the world (the initial object volume).
struct VolumePlacement {
  Eigen::Vector3d centre_world = Eigen::Vector3d::Zero();
  double extent_m = 0;      // edge length
  double voxel_size_m = 0;  // extent / resolution
  int resolution = 0;       // voxels per edge
};

/// Step 5, creation geometry: 10th/90th percentiles of the masked points per axis give centre
/// and extent; the largest axis extent times objects.padding is the cube's edge; resolution
/// objects.resolution. Points in the world frame. Needs >= 10 points (else extent 0).
VolumePlacement placeObject(const std::vector<Eigen::Vector3d>& points_world,
                            const ObjectOptions& options);

/// The claim region of one detection (ObjectOptions::claim_region), in the frame of the points
/// (the object's volume frame): per axis the 2nd-98th percentile box of the detection's points,
/// widened on every side by claim_margin x the largest 10th-90th percentile extent, then
/// stretched by claim_depth x that extent along the direction from `camera` to the 10th-90th
/// box's centre (the box and its shifted copy, bounded together). Empty with fewer than 10
/// points.
Eigen::AlignedBox3d claimRegion(const std::vector<Eigen::Vector3d>& points,
                                const Eigen::Vector3d& camera, const ObjectOptions& options);

/// An oriented box: the volume [0, size] in its own frame, placed by T_world_box.
struct OrientedBox {
  Eigen::Isometry3d T_world_box = Eigen::Isometry3d::Identity();
  Eigen::Vector3d size_m = Eigen::Vector3d::Zero();
};

/// Volumetric IoU of two oriented boxes, estimated by sampling each box on an n^3 grid of cell
/// centres (exact for axis-aligned boxes whose faces fall on the grid; error ~1/n otherwise).
double boxIoU(const OrientedBox& a, const OrientedBox& b, int n = 24);

/// Fraction of the detection mask's pixels already covered by a rendered object (object_ids
/// CV_32S or CV_16U, > 0 = some object). 0 for an empty mask.
double maskCoveredFraction(const cv::Mat& detection_mask, const cv::Mat& object_ids);

/// Pixels of a detection mask (p > 0.5) inside the image shrunk by objects.visibility_border_px:
/// the step-6 visibility count of the object it would create.
int maskVisiblePixels(const cv::Mat& mask, const ObjectOptions& options);

/// Step 5, the mask a new object is built from (beyond the paper): the largest 4-connected
/// region of the detection's mask pixels (p > 0.5, valid vertex) in which no pixel has a depth
/// jump above creation_depth_jump_m + creation_depth_jump_per_m2 * z^2 to a valid 4-neighbour,
/// plus the mask pixels next to that region without such a jump to their neighbour in it (the
/// object's own silhouette pixels).
/// Detector masks spill over silhouettes: the spilled pixels lie on the surface behind, across a
/// depth jump, and would widen the volume's 10th-90th percentile extent and enter the object's
/// first model with full weight. Returns `mask` (CV_32F, same size) with the pixels outside that
/// region set to 0; `mask` unchanged when creation_depth_jump_m is 0. `vertex` is the CV_32FC4
/// camera-frame vertex map (w = 0: invalid).
cv::Mat creationMask(const cv::Mat& mask, const cv::Mat& vertex, const ObjectOptions& options);

/// TSDF truncation (m) of a new object volume with voxels of `voxel_size_m` (beyond the paper,
/// which truncates every volume at map_truncation_voxels): objects.truncation_voxels voxels, but
/// at least objects.truncation_min_px pixel footprints (`pixel_footprint_m` = depth / fx at the
/// object) and at most map_truncation_voxels voxels.
double objectTruncation(const ObjectOptions& options, double map_truncation_voxels,
                        double voxel_size_m, double pixel_footprint_m);

/// The volume of a new object placed by placeObject: its grid and voxel size, objectTruncation
/// and the objects' integration rules (free_space_full_weight, behind_dropoff).
map::VolumeSpec objectVolumeSpec(const map::MapOptions& map_options, const ObjectOptions& options,
                                 const VolumePlacement& placement, double pixel_footprint_m);

/// All creation checks of step 5 for one unmatched detection. `reason` says which failed. Beyond
/// the paper: a mask with fewer than objects.invisible_min_px visible pixels (maskVisiblePixels)
/// creates nothing, since step 6 would delete the object as invisible in the next frame (a
/// 40x40 box lying mostly in the border band passes the size filter).
bool mayCreate(const core::Detection& d, const VolumePlacement& placement,
               const Eigen::Vector3d& camera_position_world,
               const std::vector<OrientedBox>& existing_volumes, const cv::Mat& object_ids,
               const ObjectOptions& options, std::string* reason);

/// Step 6: pixels of an object's rendered mask inside the image shrunk by
/// objects.visibility_border_px; invisible when below objects.invisible_min_px, unless (beyond
/// the paper) at least objects.invisible_inside_fraction of the pixels it renders in the image
/// lie inside that border: a small object in the middle of the view is not leaving it.
int visiblePixels(const cv::Mat& object_ids, int object_id, const ObjectOptions& options);
bool isInvisible(const cv::Mat& object_ids, int object_id, const ObjectOptions& options);

/// Step 6: mean association q_i over the object's rendered mask (q CV_32F); deleted when below
/// objects.min_mean_association. Returns 0 for an empty mask.
double meanAssociation(const cv::Mat& q, const cv::Mat& object_ids, int object_id);

/// Occlusion of an object (beyond the paper) in its own ray cast (`rendered_depth` CV_32F camera
/// z, NaN = not rendered; other objects are not drawn in it): of its rendered pixels, `hidden`
/// counts those whose measured depth (`measured_depth`, same size, NaN invalid) is nearer than
/// the rendered surface by more than margin_m + margin_per_m2 z^2 (z the rendered depth):
/// something stands in front. Pixels without a valid measurement are not hidden. `seen_through`
/// counts those whose measured depth is farther by more than the margin: the model's surface is
/// not there. If `hidden_mask` is given it receives the hidden pixels (CV_8U, 255).
struct Occlusion {
  int rendered = 0;
  int hidden = 0;
  int seen_through = 0;
  double hiddenFraction() const {
    return rendered > 0 ? static_cast<double>(hidden) / rendered : 0.0;
  }
};
Occlusion occlusion(const cv::Mat& rendered_depth, const cv::Mat& measured_depth, double margin_m,
                    double margin_per_m2, cv::Mat* hidden_mask = nullptr);
/// Object masks where the background's surface is stale (beyond the paper). `ids` / `depth` are
/// the ray cast of the background (id 0) and the objects, in which the background wins unless
/// an object lies within objects.render_margin_m behind it; `object_ids` / `object_depth` the
/// ray cast of the objects alone (-1 / NaN = none); `measured_depth` the frame's depth (NaN
/// invalid); all CV_32S / CV_32F of one size. A pixel the background took goes to the object
/// behind it when the measurement sees through the background's surface (measured > background
/// + margin) and lies on the object's surface (|measured - object| <= margin), margin =
/// margin_m + margin_per_m2 z^2 at the measured z. The background keeps a copy of a still
/// object's surface (it fuses those pixels with q_0 ~0.5); once the object moves away from the
/// camera, that copy hid it from its own detections. Returns the number of pixels given back.
int uncoverStaleBackground(cv::Mat* ids, const cv::Mat& depth, const cv::Mat& object_ids,
                           const cv::Mat& object_depth, const cv::Mat& measured_depth,
                           double margin_m, double margin_per_m2);

/// Hidden: at least objects.hidden_fraction of the rendered pixels are hidden; an object that
/// was hidden (`was_hidden`) stays so until fewer than objects.visible_again_fraction are (never
/// with hidden_fraction 0 or nothing rendered).
bool isHidden(const Occlusion& occlusion, const ObjectOptions& options, bool was_hidden = false);
/// Moved on (beyond the paper): of the object's rendered pixels that nothing hides, at least
/// half are seen through (the measurement lies behind its surface), and they are at least a tenth
/// of all it renders. Such an object is not hidden but elsewhere: a hidden object is held at its
/// last pose, and once its unhidden part shows the scene behind that pose, a hold would keep a
/// stale pose.
bool movedOn(const Occlusion& occlusion);
/// Leaving the view (beyond the paper). `wide_ids` is the object's own ray cast over a view
/// wider than the frame's (its pixels == object_id), `frame` the frame's rectangle in it:
/// the fraction of its pixels inside `frame` (1 when nothing is rendered).
double inViewFraction(const cv::Mat& wide_ids, int object_id, const cv::Rect& frame);
/// Whether any pixel of the object's mask lies on the outermost rows or columns of the image:
/// only then can part of it be outside.
bool touchesImageEdge(const cv::Mat& object_ids, int object_id);
/// Leaving: less than objects.leaving_fraction of the projection is in view; an object that was
/// leaving (`was_leaving`) stays so until at least objects.in_view_again_fraction is (never with
/// leaving_fraction 0).
bool isLeaving(double in_view_fraction, const ObjectOptions& options, bool was_leaving = false);

/// Objects hidden on more than objects.max_hidden_frames frames in a row are deleted.
bool hiddenTooLong(int consecutive_hidden_frames, const ObjectOptions& options);

/// Objects whose tracking failed on more than objects.max_lost_frames frames in a row are
/// deleted (not in the paper: a stale pose re-acquires the object at a wrong place).
bool lostTooLong(int consecutive_lost_frames, const ObjectOptions& options);

/// How far an object moved between the volume poses T_world_a and T_world_b: its centre
/// (`centre`: volume frame, m) by centre_m, its orientation by angle_deg.
struct PoseChange {
  double centre_m = 0.0;
  double angle_deg = 0.0;
};
PoseChange poseChange(const Eigen::Isometry3d& T_world_a, const Eigen::Isometry3d& T_world_b,
                      const Eigen::Vector3d& centre);

/// Still objects (objects.still_translation_m, still_rotation_deg; not in the paper): an
/// object whose tracked poses over the last objects.still_frames frames (`window`: world poses,
/// oldest first) all lie within those bounds of the newest is still: held at that pose, so
/// neither the depth noise's jitter nor the slow drift of a model tracked against itself moves
/// it. It moves again once a tracked pose leaves the held one by more (isStillAt).
bool looksStill(const std::vector<Eigen::Isometry3d>& window, const Eigen::Vector3d& centre,
                const ObjectOptions& options);
/// A held still object starting to move slowly (a push, a spin): its tracked pose's change from
/// the held one (`offsets`, one per held frame, oldest first) grew on each of the last
/// kStartFrames frames and reached a quarter of the bound in the centre's distance
/// (objects.still_translation_m), or half of it in the angle (objects.still_rotation_deg; a spin
/// in place leaves the centre where it is, and the angle jitters more). Depth noise jitters the
/// offsets up and down; a start grows one frame after frame, long before it reaches the bound.
constexpr int kStartFrames = 3;
bool startsMoving(const std::vector<PoseChange>& offsets, const ObjectOptions& options);
/// Whether the tracked pose T_world_tracked lies within the still bounds of T_world_held.
bool isStillAt(const Eigen::Isometry3d& T_world_held, const Eigen::Isometry3d& T_world_tracked,
               const Eigen::Vector3d& centre, const ObjectOptions& options);
/// The data's verdict on a held object whose tracked pose left the still bounds: the frame's
/// object pixels evaluated at the held pose and at the tracked one, on the pixels that land on
/// the model at both (`common` of `valid` at the tracked pose). `cost_change` is the robust
/// cost at the held pose minus that at the tracked one, `held_cost` the cost at the held pose
/// (any common unit). The object stays held while the tracked pose fits the frame better by
/// less than objects.still_release_cost of the tracked pose's cost, and at least half the
/// pixels still land on the model at the held pose: a far or weakly constrained object's
/// tracked pose wanders along a nearly flat cost, and a moved object leaves the held pose's
/// cost well above the tracked one's. Always false with still_release_cost 0.
bool fitKeepsStill(double cost_change, double held_cost, int common, int valid,
                   const ObjectOptions& options);

/// Step 5, growing: whole blocks (block_voxels per block) to add on the low and high side of
/// each axis so that every point (volume frame, metres; volume spans [0, dims*block*voxel]) lies
/// inside. Growth per side is capped at `max_blocks_per_side`.
struct GrowPlan {
  Eigen::Vector3i add_low = Eigen::Vector3i::Zero();
  Eigen::Vector3i add_high = Eigen::Vector3i::Zero();
  bool any() const { return (add_low.array() > 0).any() || (add_high.array() > 0).any(); }
};
GrowPlan planGrowth(const std::vector<Eigen::Vector3d>& points_volume,
                    const Eigen::Vector3i& dims_blocks, double voxel_size_m, int block_voxels,
                    int max_blocks_per_side);

}  // namespace emf::em
