// Options of the E-step (section `em`) and of the object lifecycle (section `objects`).
// Defaults are docs/method.md's; where they depart from the paper: docs/deviations.md.
#pragma once

#include <string>
#include <vector>

#include "common/option_binder.h"

namespace emf::em {

enum class Association { kEm, kPfg };
inline const ChoiceNames<Association>& associationNames() {
  static const ChoiceNames<Association> names = {{Association::kEm, "em"},
                                                 {Association::kPfg, "pfg"}};
  return names;
}

struct EmOptions {
  double sigma_m = 0.02;
  double alpha = 0.8;
  double p_uniform = 1.0;
  double min_weight = 0.5;
  /// em: the E-step (docs/method.md#e-step); pfg: the paper's "w/o assoc." ablation (q_i = p_fg).
  Association association = Association::kEm;

  void bind(OptionBinder& b) {
    b.real("sigma_m", sigma_m, 1e-5, 1.0, "m", "Laplace scale of the SDF residual");
    b.real("alpha", alpha, 0.0, 1.0, "", "inlier mixture weight");
    b.real("p_uniform", p_uniform, 0.0, 1e6, "", "uniform outlier likelihood p_U");
    b.real("min_weight", min_weight, 0.0, 128.0, "",
           "voxels with a lower TSDF weight count as unobserved in the E-step");
    b.choice("association", association, associationNames(),
             "em = association likelihoods; pfg = foreground probability only (ablation)");
  }
};

struct ObjectOptions {
  int min_detection_px = 40;
  std::vector<std::string> exclude_classes = {
      "traffic light", "fire hydrant", "stop sign",   "parking meter", "bench",
      "couch",         "potted plant", "bed",         "dining table",  "toilet",
      "oven",          "sink",         "refrigerator"};
  bool track_person = false;
  double match_iou = 0.2;
  /// A detection IoU matching left that holds at least this share of the ray-cast mask of an
  /// object of its class that no detection matched is a mask spilled over that object
  /// (em::matchSpilledMasks): the object counts as detected, takes foreground counts on its own
  /// ray-cast pixels only, and no new object is made from it.
  /// 0 = off (the paper); docs/deviations.md.
  double match_spilled = 0.7;
  /// In the ray-cast object masks (matching, foreground counts, creation check, overlays) an
  /// object's surface stays in front of the background's copy of it unless it lies more than
  /// this much deeper, m (the authors' code: 5 cm).
  double render_margin_m = 0.05;
  /// In those masks the object also wins where the frame's depth sees through the background's
  /// surface and lies on the object's (em::uncoverStaleBackground). false = the map alone (the
  /// paper); docs/deviations.md.
  bool mask_measured_depth = true;
  double existence_delete = 0.1;
  double padding = 2.0;
  /// An object claims pixels in the E-step only in the region its detections showed (the union
  /// of their point boxes, widened by claim_margin and stretched claim_depth away from the
  /// camera, in the object's frame). false = its whole volume (the paper); docs/deviations.md.
  bool claim_region = true;
  double claim_margin = 0.5;
  double claim_depth = 1.0;
  int resolution = 64;
  double max_create_distance_m = 5.0;
  double max_volume_iou = 0.5;
  double max_mask_covered = 0.5;
  int invisible_min_px = 1600;
  int visibility_border_px = 20;
  /// The visibility rule ray-casts the objects at most this wide, px (its pixel thresholds
  /// scale with it). 0 = the frame's size (the paper); a speed deviation, docs/deviations.md.
  int visibility_width = 160;
  /// An object with fewer than invisible_min_px pixels inside the border stays visible when
  /// this fraction of what it renders lies inside the border (small, not leaving). 0 = off.
  double invisible_inside_fraction = 0.9;
  double min_mean_association = 0.1;
  /// An object whose tracking failed on more frames in a row than this (camera tracked) is
  /// retired: its pose is stale. 0 = never (the paper has no such rule).
  int max_lost_frames = 15;
  /// TSDF weight cap W_max of object volumes (the paper: 64, map.max_weight for every volume).
  /// A model fused at its own tracked poses follows their errors over about W_max frames; a
  /// rigid object's model can remember longer than the background, which must forget what
  /// moved out of it. docs/deviations.md.
  double max_weight = 127.0;
  /// An object with this fraction of its own ray cast behind nearer measured surfaces is
  /// hidden: held still in the world, not tracked or integrated, not retired as lost. 0 = off
  /// (the paper, which deletes it as invisible); docs/method.md#hidden-and-leaving-objects.
  double hidden_fraction = 0.5;
  /// A hidden object is tracked again once fewer than this fraction of its pixels are hidden.
  double visible_again_fraction = 0.1;
  /// Objects hidden on more than this many frames in a row are deleted: an object moved while
  /// hidden would be re-acquired from a stale pose. 0 = never.
  int max_hidden_frames = 300;
  /// An object with less than this fraction of its projection inside the image is leaving the
  /// view: held like a hidden one (the sliver in view slides along the border), but still
  /// retired when invisible. 0 = off (the paper).
  double leaving_fraction = 0.0;
  /// An object held as leaving is tracked again once at least this fraction of its projection
  /// is inside the image (at least leaving_fraction).
  double in_view_again_fraction = 0.6;
  int max_objects = 8;
  /// A retired object stays dormant with its model this many frames; a detection whose points
  /// fit a dormant or stale object re-attaches to it with its id and trajectory. 0 = delete at
  /// once (the paper); docs/method.md#re-identification.
  int reidentify_frames = 300;
  /// Share of a detection's points within the inlier band of a model (after the fit, with at
  /// least half of them on its observed surface) for the detection to re-attach to it.
  double reidentify_min_inliers = 0.8;
  /// A new object is tracked at once but reported (outputs, C API) once this many detections
  /// matched it, with its earlier poses; one missed by two detection frames is dropped
  /// unreported. 1 = at once (the paper); docs/method.md#confirmation.
  int confirm_detections = 2;
  /// An object is not created when its first integration leaves less than this fraction of the
  /// voxel pool free: the background (and the objects' growth) keep room in a fixed pool.
  double min_free_pool_fraction = 0.25;
  bool free_space_full_weight = false;
  /// Object volumes weight an observation behind the surface (d < -voxel) by a linear drop-off
  /// to 0 at -truncation (Voxblox's rule; off, as in the paper): the projective distance behind
  /// a surface overestimates the true one near edges seen from the side. Off by default: it
  /// weakens the model's inside, which re-acquisition leans on; docs/deviations.md.
  bool behind_dropoff = false;
  bool filter_depth = false;
  /// With filter_depth off, the E-step, object tracking and creation read the raw depth through
  /// a bilateral filter of their own: window radius, px (0 = raw), and range sigma, m.
  int depth_filter_radius_px = 1;
  double depth_filter_sigma_m = 0.02;
  /// With filter_depth off, the objects' own hole margin, px (preprocess.hole_margin_px).
  int depth_hole_margin_px = 0;
  int max_grow_blocks = 4;
  /// A new object is built from the largest part of its mask without a depth jump above
  /// creation_depth_jump_m + creation_depth_jump_per_m2 z^2 between neighbours, m (a mask that
  /// spills onto the wall behind). 0 = the whole mask (the paper).
  double creation_depth_jump_m = 0.03;
  double creation_depth_jump_per_m2 = 0.01;
  /// TSDF truncation of object volumes, voxels (the paper: 10, as the background's; 10 voxels
  /// span a large part of a new object and blur its model; a thinner band keeps small and thin
  /// models sharp); docs/deviations.md.
  double truncation_voxels = 3.33;
  /// ... but at least this many pixel footprints at the object's depth, and at most
  /// map.truncation_voxels (coarse images hold too few measurements in a thin band).
  double truncation_min_px = 4.0;
  /// Huber delta of object tracking as a fraction of the object's truncation (the paper's 0.2;
  /// the camera has its own, track.huber_truncation_factor).
  double huber_truncation_factor = 0.2;
  /// Object tracking's LM stops once its Gauss-Newton step is shorter than this (m and rad mixed;
  /// far below what an object's depth pins down per frame, docs/method.md#object-tracking; the
  /// camera has its own, track.early_exit_step). 0 = LM's own test only (the paper).
  double track_early_exit_step = 1e-3;
  /// Pull of an object's tracked rotation towards its constant-velocity prediction:
  /// E = this x |rotation off the prediction, rad|^2 / 2 in data-term units (a pixel with full
  /// weight adds r^2 / 2, r in m), for 640x480, scaled with the image area. 0 = off (the paper).
  double motion_prior_rotation = 1.0;
  /// Still objects (em::looksStill; docs/method.md#object-tracking): held where they stand
  /// once their tracked poses over still_frames frames stay within still_translation_m (m, of
  /// the centre) and still_rotation_deg of the newest; released when a tracked pose leaves
  /// those bounds or starts to (em::startsMoving). Not in the paper: a still object's own
  /// tracking jitters and drifts, and movers that start slowly lag a few frames
  /// (docs/deviations.md). 0 = off (the paper).
  double still_translation_m = 0.02;
  double still_rotation_deg = 2.0;
  int still_frames = 15;
  /// A held object whose tracked pose leaves the still bounds stays held while that pose fits
  /// the frame's depth better than the held one by less than this fraction of its robust cost
  /// (em::fitKeepsStill). 0 = released by the bounds alone.
  double still_release_cost = 0.2;

  void bind(OptionBinder& b) {
    // Pixel thresholds refer to 640x480 images; the SLAM scales them with the image width.
    b.integer("min_detection_px", min_detection_px, 0, 10000, "px",
              "detections with a box side below this are dropped (at 640x480)");
    b.textList("exclude_classes", exclude_classes, "classes that never create objects");
    b.boolean("track_person", track_person, "track people as objects that are never rendered");
    b.real("match_iou", match_iou, 0.0, 1.0, "", "min mask IoU to match a detection");
    b.real("match_spilled", match_spilled, 0.0, 1.0, "",
           "an unmatched detection holding this share of the mask of an unmatched object of its "
           "class is a mask spilled over it (0 = off, the paper)");
    b.real("render_margin_m", render_margin_m, 0.0, 1.0, "m",
           "in the ray-cast object masks an object stays in front of the background unless it "
           "lies more than this deeper");
    b.boolean("mask_measured_depth", mask_measured_depth,
              "in the object masks an object wins where the frame's depth sees through the "
              "background's surface onto it (false = the map alone, the paper)");
    b.real("existence_delete", existence_delete, 0.0, 1.0, "",
           "delete objects with Ex/(Ex+NonEx) below");
    b.real("padding", padding, 1.0, 10.0, "", "new volume extent / detected extent");
    b.boolean("claim_region", claim_region,
              "objects claim pixels (E-step) only in the region their detections showed (false = "
              "the whole volume, the paper)");
    b.real("claim_margin", claim_margin, 0.0, 10.0, "",
           "... the detections' point boxes widened on every side by this x their largest extent");
    b.real("claim_depth", claim_depth, 0.0, 10.0, "",
           "... and stretched this x their largest extent away from the camera");
    b.integer("resolution", resolution, 8, 512, "voxels", "new object volume resolution");
    b.real("max_create_distance_m", max_create_distance_m, 0.0, 100.0, "m",
           "objects farther from the camera are not created");
    b.real("max_volume_iou", max_volume_iou, 0.0, 1.0, "",
           "no creation if volume IoU with an existing volume is >= this");
    b.real("max_mask_covered", max_mask_covered, 0.0, 1.0, "",
           "no creation if this fraction of the mask is covered by objects");
    b.integer("invisible_min_px", invisible_min_px, 0, 1000000, "px",
              "objects rendering fewer pixels (inside the border) are deleted (at 640x480)");
    b.integer("visibility_border_px", visibility_border_px, 0, 1000, "px",
              "image border ignored by the visibility test (at 640x480)");
    b.integer("visibility_width", visibility_width, 0, 16384, "px",
              "the visibility test's ray cast runs at this image width, at most the frame's "
              "(0 = the frame's, the paper)");
    b.real("invisible_inside_fraction", invisible_inside_fraction, 0.0, 1.0, "",
           "an object below invisible_min_px stays visible with this fraction of its rendered "
           "pixels inside the border (0 = off, the paper)");
    b.real("min_mean_association", min_mean_association, 0.0, 1.0, "",
           "objects whose mean association over their mask is below this are deleted");
    b.integer("max_lost_frames", max_lost_frames, 0, 100000, "frames",
              "objects whose tracking failed on more frames in a row are deleted (0 = never)");
    b.real("max_weight", max_weight, 1.0, 127.0, "",
           "TSDF weight cap W_max of object volumes (storage limit 127; the paper: 64, as "
           "map.max_weight)");
    b.real("hidden_fraction", hidden_fraction, 0.0, 1.0, "",
           "an object with this fraction of its ray cast behind nearer surfaces is hidden: held "
           "still, not tracked, not deleted as lost or invisible (0 = off, the paper)");
    b.real("visible_again_fraction", visible_again_fraction, 0.0, 1.0, "",
           "a hidden object is tracked again once fewer than this fraction of its pixels are "
           "hidden (at most hidden_fraction)");
    b.integer("max_hidden_frames", max_hidden_frames, 0, 100000, "frames",
              "objects hidden on more frames in a row are deleted (0 = never)");
    b.real("leaving_fraction", leaving_fraction, 0.0, 1.0, "",
           "an object with less than this fraction of its projection inside the image is held "
           "still, not tracked (0 = off, the paper)");
    b.real("in_view_again_fraction", in_view_again_fraction, 0.0, 1.0, "",
           "an object held as leaving is tracked again once this fraction of its projection is "
           "inside the image (at least leaving_fraction)");
    b.boolean("free_space_full_weight", free_space_full_weight,
              "object volumes integrate free space with weight 1 whatever q (the authors' "
              "rule; off: weighted by q, which keeps other surfaces from eroding the object)");
    b.boolean("behind_dropoff", behind_dropoff,
              "object volumes weight observations behind the surface down to 0 at -truncation "
              "(off: full weight, the paper)");
    b.boolean("filter_depth", filter_depth,
              "the E-step and the objects use the camera's bilateral-filtered depth (the paper; "
              "off: the raw depth through objects.depth_filter_*, which keeps silhouettes sharp)");
    b.integer("depth_filter_radius_px", depth_filter_radius_px, 0, 10, "px",
              "with filter_depth off: the objects' bilateral window radius (0 = raw depth)");
    b.real("depth_filter_sigma_m", depth_filter_sigma_m, 1e-4, 10.0, "m",
           "with filter_depth off: the objects' bilateral range sigma");
    b.integer("depth_hole_margin_px", depth_hole_margin_px, 0, 5, "px",
              "with filter_depth off: the objects' hole margin (see preprocess.hole_margin_px)");
    b.integer("max_objects", max_objects, 0, 64, "",
              "object volumes alive at once (sizes the per-frame buffers)");
    b.integer("reidentify_frames", reidentify_frames, 0, 100000, "frames",
              "a deleted object's model is kept this long for a later detection that fits it to "
              "re-attach (same id; 0 = delete at once, the paper)");
    b.real("reidentify_min_inliers", reidentify_min_inliers, 0.0, 1.0, "",
           "share of a detection's points within the inlier band of a model for it to "
           "re-attach");
    b.integer("confirm_detections", confirm_detections, 1, 100, "detections",
              "a new object is reported once this many detections matched it (1 = at once, "
              "the paper)");
    b.real("min_free_pool_fraction", min_free_pool_fraction, 0.0, 1.0, "",
           "no object is created when it would leave less than this fraction of the voxel pool "
           "free (room for the background; 0 = off)");
    b.integer("max_grow_blocks", max_grow_blocks, 0, 64, "blocks",
              "most blocks an object volume grows per side on one detection");
    b.real("creation_depth_jump_m", creation_depth_jump_m, 0.0, 10.0, "m",
           "a new object is built from the largest part of its mask without a depth jump above "
           "this (+ creation_depth_jump_per_m2 x depth^2) between neighbours (0 = whole mask)");
    b.real("creation_depth_jump_per_m2", creation_depth_jump_per_m2, 0.0, 10.0, "m/m^2",
           "depth-dependent part of the creation mask's depth-jump threshold");
    b.real("truncation_voxels", truncation_voxels, 1.0, 100.0, "voxels",
           "TSDF truncation of object volumes (the paper: 10, as map.truncation_voxels)");
    b.real("truncation_min_px", truncation_min_px, 0.0, 100.0, "px",
           "object truncation at least this many pixel footprints at the object's depth, at "
           "most map.truncation_voxels");
    b.real("huber_truncation_factor", huber_truncation_factor, 0.0, 10.0, "truncation",
           "Huber delta of object tracking as a fraction of the object's truncation");
    b.real("track_early_exit_step", track_early_exit_step, 0.0, 1.0, "m|rad",
           "object tracking stops when its Gauss-Newton step is below this (0 = LM's own test, "
           "the paper)");
    b.real("motion_prior_rotation", motion_prior_rotation, 0.0, 1e6, "",
           "pull of an object's tracked rotation towards its prediction, in data-term units at "
           "640x480, scaled with the image area (0 = off, the paper)");
    b.real("still_translation_m", still_translation_m, 0.0, 1.0, "m",
           "an object whose tracked poses over still_frames frames keep its centre within this "
           "and its orientation within still_rotation_deg is held still until one does not (0 "
           "= off, the paper)");
    b.real("still_rotation_deg", still_rotation_deg, 0.0, 180.0, "deg",
           "rotation bound of a still object (with still_translation_m)");
    b.integer("still_frames", still_frames, 2, 1000, "frames",
              "frames an object's tracked poses must stay within the still bounds to hold it");
    b.real("still_release_cost", still_release_cost, 0.0, 100.0, "",
           "a held object leaving the still bounds stays held while its tracked pose lowers the "
           "frame's cost by less than this fraction (0 = released by the bounds alone)");
  }
};

}  // namespace emf::em
