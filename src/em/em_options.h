// Options of the E-step (section `em`) and of the object lifecycle (section `objects`).
// Defaults are docs/method.md's; where they depart from the paper: docs/deviations.md.
#pragma once

#include <string>
#include <vector>

#include "common/option_binder.h"

namespace emf::em {

struct EmOptions {
  double sigma_m = 0.02;
  double alpha = 0.8;
  double p_uniform = 1.0;
  double min_weight = 0.5;
  /// em: the E-step (docs/method.md#e-step); pfg: the paper's "w/o assoc." ablation (q_i = p_fg).
  std::string association = "em";

  void bind(OptionBinder& b) {
    b.real("sigma_m", sigma_m, 1e-5, 1.0, "m", "Laplace scale of the SDF residual");
    b.real("alpha", alpha, 0.0, 1.0, "", "inlier mixture weight");
    b.real("p_uniform", p_uniform, 0.0, 1e6, "", "uniform outlier likelihood p_U");
    b.real("min_weight", min_weight, 0.0, 128.0, "",
           "voxels with a lower TSDF weight count as unobserved in the E-step");
    b.choice("association", association, {"em", "pfg"},
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
  /// In the ray-cast object masks (matching detections, the foreground counts, the creation
  /// check, the overlay images) an object's surface stays in front of the background's unless
  /// it lies more than this much deeper: the background keeps a copy of a still object's surface
  /// (it integrates those pixels with its association), and with one background voxel (the
  /// previous margin) that copy hid half of a chair at 2.4 m (occlusion, 640x480: IoU with its
  /// detections 0.38-0.43, duplicates created later). The authors' code uses 5 cm. Metres.
  double render_margin_m = 0.05;
  /// In those masks, where the frame's depth sees through the background's surface and lies on
  /// an object's, the object wins (em::uncoverStaleBackground; not in the paper, where the map
  /// alone decides): the background's copy of a still object's surface stays when the object
  /// moves away from the camera and hid it from its detections (occlusion preset, 640x480: the
  /// chair, still for 390 frames, then 20 cm behind that copy; its detections matched with IoU
  /// 0.01-0.09 and created duplicates). The margin is render_margin_m plus
  /// track.inlier_noise_per_m2 z^2. false = the map alone.
  bool mask_measured_depth = true;
  double existence_delete = 0.1;
  double padding = 2.0;
  /// Claim region (not in the paper, where an object's E-step covers its whole volume): an
  /// object claims pixels only where its detections showed it, the box of each matched
  /// detection's points (2nd-98th percentile per axis of the object's frame) widened on every
  /// side by claim_margin x the detection's largest 10th-90th percentile extent and stretched
  /// claim_depth x that extent away from the camera (its unseen back lies behind what it
  /// showed), the union over the object's life. A volume padded 2x around the object also
  /// holds the space beside it, where an undetected mover claimed by the object's unobserved
  /// voxels became part of its model and dragged it (occlusion preset, seed 1, 640x480: the
  /// chair 7.2 cm off at 79 %). false = the whole volume (the paper).
  bool claim_region = true;
  double claim_margin = 0.5;
  double claim_depth = 1.0;
  int resolution = 64;
  double max_create_distance_m = 5.0;
  double max_volume_iou = 0.5;
  double max_mask_covered = 0.5;
  int invisible_min_px = 1600;
  int visibility_border_px = 20;
  /// The visibility rule (invisible_min_px, min_mean_association) ray-casts the objects every
  /// frame at this image width (the frame's aspect; never more than the frame's width), 0 = the
  /// frame's size (the paper). Its pixel thresholds scale with this width. At 640x480 with 3
  /// objects the full-size cast took 19.5 ms per frame, a third of the frame (README).
  int visibility_width = 320;
  /// An object with fewer than invisible_min_px pixels inside the border is still visible when
  /// at least this fraction of the pixels it renders in the image lie inside the border: it is
  /// small, not leaving the view. The paper (0 = off) deletes it: the motion plugin's toy cars
  /// (partial models of 380-400 px at 320x240, in the middle of the image) were deleted 5 times
  /// in 150 frames.
  double invisible_inside_fraction = 0.9;
  double min_mean_association = 0.1;
  /// Objects whose tracking failed on more than this many frames in a row (with the camera
  /// tracked) are deleted: their pose is stale, and tracking from it re-acquires the object at
  /// a wrong place (cars preset: car 2 lost near frame 90, "found" 2 m off). A detection
  /// re-creates it where it is. 0 = never (the paper has no such rule).
  int max_lost_frames = 15;
  /// Occlusion (not in the paper, which renders masks with nearer objects in front and so
  /// deletes an object hidden behind another as invisible): an object whose own ray cast (at
  /// visibility_width, other objects not drawn) has at least this fraction of its pixels behind
  /// nearer measured surfaces (by more than its truncation + track.inlier_noise_per_m2 z^2) is
  /// hidden. A hidden object is not tracked on the next frame (its few visible pixels pull it
  /// towards whatever is in front, and LM then fails or drifts): its pose is held still in the
  /// world, it is not integrated, its lost-frame count does not grow, and its visibility counts
  /// its own ray cast inside the border. 0 = off (the paper).
  double hidden_fraction = 0.5;
  /// A hidden object is tracked again once fewer than this fraction of its pixels are hidden
  /// (at most hidden_fraction). Tracking a half-uncovered object lets the occluder still in its
  /// volume drag it along as it slides away (occlusion preset, 320x240: the chair re-acquired
  /// ~35 cm off with 0.5).
  double visible_again_fraction = 0.1;
  /// Objects hidden on more than this many frames in a row are deleted: an object moved while
  /// hidden would be re-acquired from a stale pose. 0 = never.
  int max_hidden_frames = 300;
  /// Leaving the view (not in the paper): an object of which less than this fraction of its
  /// model's projection lies inside the image (its own ray cast over a view twice as wide and
  /// high, at half the frame's resolution; only cast when its visibility cast touches the image
  /// edge) is held on the next frame like a hidden one: its pose held still in the world, not
  /// tracked or integrated. The sliver left in view does not fix the pose: it slides along the
  /// border (occlusion preset, 640x480: the suitcase 15-55 cm off on its last 6 frames in
  /// view; a turning box in tests/pipeline/slam_leaving_test.cpp 1.4-33 cm). Unlike a hidden
  /// object it is still deleted when invisible or by its mean association, so the model of a
  /// mover that left does not stay. 0 = off (the paper).
  double leaving_fraction = 0.5;
  /// An object held as leaving is tracked again once at least this fraction of its projection
  /// is inside the image (at least leaving_fraction).
  double in_view_again_fraction = 0.6;
  int max_objects = 8;
  /// Re-identification (not in the paper, which deletes and starts over): an object deleted by
  /// a rule (lost, invisible, unassociated, hidden, non-existent) keeps its model, dormant, for
  /// this many frames. A detection that would create a new object is first fitted to the lost
  /// and the dormant objects' models (from their last pose and from the detection's centre at
  /// 12 headings); one that fits (reidentify_min_inliers) re-attaches to that object with its
  /// id and trajectory. 0 = delete at once (the paper).
  int reidentify_frames = 300;
  /// Share of a detection's points within the inlier band of a model (after the fit, with at
  /// least half of them on its observed surface) for the detection to re-attach to it.
  double reidentify_min_inliers = 0.8;
  /// Confirmation (not in the paper, where an object exists from its first detection): a new
  /// object is tracked and fused from its first detection but reported (outputs, C API) only
  /// once this many detections matched it, with the poses of the frames before (a false
  /// detection, a blob on a wall, is seldom detected again). A tentative object missed by two
  /// detection frames is deleted unreported. 1 = reported at once (the paper).
  int confirm_detections = 2;
  /// An object is not created when its first integration leaves less than this fraction of the
  /// voxel pool free: the background (and the objects' growth) keep room in a fixed pool.
  double min_free_pool_fraction = 0.25;
  bool free_space_full_weight = false;
  bool filter_depth = false;
  /// With filter_depth off, the E-step, object tracking and object creation read the raw depth
  /// through a light bilateral filter of their own: this window radius (0 = the raw depth) and
  /// range sigma (the spatial sigma is preprocess.sigma_space_px). The camera's 7x7 filter with
  /// a 4 cm range sigma blends object silhouettes with the surface behind; the raw depth keeps
  /// the sensor's disparity steps (about 2 cm at 2.4 m at 320x240), which shake a small object's
  /// pose. 3 seeds each of the cars and occlusion presets at 320x240, mean object ATE car 1 /
  /// car 2 / bear / chair / suitcase: raw 5.2 / 4.2 / 3.6 / 0.7 / 0.3 cm; 3x3 at 2 cm 3.7 / 3.0
  /// / 2.6 / 0.8 / 0.4; 5x5 at 2 cm 3.8 / 3.8 / 2.6 / 0.9 / 0.5; the camera's filter 4.3 / 6.3 /
  /// 2.9 / 1.0 / 0.6.
  int depth_filter_radius_px = 1;
  double depth_filter_sigma_m = 0.02;
  /// With filter_depth off, the objects' own hole margin (preprocess.hole_margin_px for their
  /// depth). cars preset 640x480, seed 1, with preprocess.hole_margin_px 1: car 1 / car 2 ATE
  /// over 600 frames 2.42 / 1.87 cm with 0, 3.33 / 1.85 with 1, 4.66 / 2.13 with 2; over 150
  /// frames 1.85 / 1.26, 1.90 / 1.40, 2.15 / 1.53. A small object's silhouette touches dropouts
  /// all around, and a margin there takes away much of its few pixels.
  int depth_hole_margin_px = 0;
  int max_grow_blocks = 4;
  /// A new object is built from the largest depth-continuous part of its detection mask: mask
  /// pixels with a depth jump above creation_depth_jump_m + creation_depth_jump_per_m2 * z^2 to
  /// a 4-neighbour separate regions (creationMask in em/object_rules.h). A detector's mask that
  /// spills past the object's silhouette onto a surface behind it otherwise widens the volume
  /// and puts that surface into the object's first model. 0 = the whole mask (the paper).
  double creation_depth_jump_m = 0.03;
  double creation_depth_jump_per_m2 = 0.01;
  /// TSDF truncation of object volumes, in their voxels (map.truncation_voxels, 10, is the
  /// paper's for every volume). A new object's volume is its padded extent in 64 voxels, so 10
  /// voxels are 30 % of the object: the projective distances of its far side then reach into its
  /// near side's band, and a car's or a bear's model comes out blurred (3 seeds each of the cars
  /// and occlusion presets, 320x240: mean object ATE car 1 / car 2 / bear / chair 5.0 / 8.1 /
  /// 4.8 / 1.3 cm at 10 voxels, 5.2 / 4.2 / 3.6 / 0.7 at 5 with the pixel floor below; car 1 loses
  /// coverage at 3-4).
  double truncation_voxels = 5.0;
  /// ... but at least this many pixel footprints at the object's depth (z / fx at creation), and
  /// never more than map.truncation_voxels: with few, coarse pixels per voxel (160x120, a car
  /// 2.3 m away: 1.8 cm per pixel, 0.57 cm voxels) a 5-voxel band holds too few measurements and
  /// the car was lost on its second frame.
  double truncation_min_px = 4.0;
  /// Huber delta of object tracking as a fraction of the object's truncation (the paper's 0.2
  /// for every volume). The camera has its own, track.huber_truncation_factor: a tighter delta
  /// there rejects unmodelled movers, but on the cars preset it costs the objects accuracy.
  double huber_truncation_factor = 0.2;
  /// Motion prior of object tracking: a pull of the object's rotation towards its
  /// constant-velocity prediction, E_p = motion_prior_rotation |d_w|^2 / 2 (d_w the rotation
  /// away from the prediction, radians) in the units of the data term (a pixel with full map
  /// weight and association adds r^2 / 2, r in metres), given for 640x480 and scaled with the
  /// image area (the data term's pixel count). The depth noise turns a small object's fit by
  /// 0.2-0.3 deg per frame, most of its error at the camera's distance; the prior damps that
  /// jitter where the object's few pixels pin the rotation down least. cars preset, 640x480,
  /// 150 frames, seed 1, car 1 / car 2 ATE at 0 / 1 / 3 / 10: 2.01 / 1.84 / 1.75 / 3.34 and
  /// 1.55 / 1.46 / 1.44 / 1.79 cm; but 3 made the motion plugin's partial car model fail worse
  /// on 600 frames (car 1 3.71 / 3.82 / 5.29 cm at 0 / 1 / 3). 0 = off (the paper).
  double motion_prior_rotation = 1.0;

  void bind(OptionBinder& b) {
    // Pixel thresholds refer to 640x480 images; the SLAM scales them with the image width.
    b.integer("min_detection_px", min_detection_px, 0, 10000, "px",
              "detections with a box side below this are dropped (at 640x480)");
    b.textList("exclude_classes", exclude_classes, "classes that never create objects");
    b.boolean("track_person", track_person, "track people as objects that are never rendered");
    b.real("match_iou", match_iou, 0.0, 1.0, "", "min mask IoU to match a detection");
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
    b.real("motion_prior_rotation", motion_prior_rotation, 0.0, 1e6, "",
           "pull of an object's tracked rotation towards its prediction, in data-term units at "
           "640x480, scaled with the image area (0 = off, the paper)");
  }
};

}  // namespace emf::em
