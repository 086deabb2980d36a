// Options of the map: the fixed voxel-block pool and the volumes (section `map`).
#pragma once

#include "common/option_binder.h"

namespace emf::map {

struct MapOptions {
  /// Size of the one voxel-block pool allocated at start-up (all volumes draw from it).
  int memory_mb = 256;
  /// Background voxel edge length.
  double background_voxel_m = 0.01;
  /// Background extent in voxels per axis (512 at 1 cm = 5.12 m, as in the paper).
  int background_resolution = 512;
  /// Truncation distance in voxels (docs/method.md#integration).
  double truncation_voxels = 10.0;
  /// Weight cap W_max of the background (objects: objects.max_weight).
  double max_weight = 64.0;
  /// Each background block of the frame's truncation band is integrated on every n-th frame
  /// that sees it (a 3-D checkerboard of n phases; new blocks at once), each observation weighing
  /// n (a voxel averages and forgets over as many frames): 1/n of the blocks per frame. 1 = every
  /// frame (the paper); 2 halves the background's integration at the same accuracy
  /// (docs/deviations.md).
  int integrate_every = 2;
  /// The background's blocks of the frame's truncation band are found from every n-th pixel in x
  /// and y (a block is 8 voxels across, far wider than a pixel's footprint). 1 = every pixel.
  int mark_stride = 1;
  /// Integrate free-space voxels with weight 1 whatever the association (authors' code).
  bool free_space_full_weight = true;
  /// Initial camera placement: offset of the camera from the background volume centre along
  /// its viewing axis, as a fraction of the extent (0.5 = centre of one face, looking in).
  double initial_camera_face_offset = 0.5;
  /// The background follows the camera (docs/architecture.md#a-map-that-follows-the-camera):
  /// once the camera sees past the grid (more than follow_outside_fraction of the last frame's
  /// pixels measured a surface outside it), the grid moves by whole blocks while the point the
  /// first camera saw at its centre (initial_camera_face_offset times the extent ahead of the
  /// camera) is farther than follow_trigger_m (at least one block) from the centre along a
  /// grid axis; the blocks that leave the grid are meshed into the background mesh and return
  /// their slots to the pool. A scene that fits in the grid never moves it.
  bool follow_camera = true;
  double follow_trigger_m = 1.0;
  double follow_outside_fraction = 0.02;
  /// Ray casting: nearest and farthest camera z rendered.
  double raycast_min_depth_m = 0.1;
  double raycast_max_depth_m = 8.0;
  /// Ray casting: step in front of a surface as a fraction of the voxel's psi (at least one
  /// voxel). Below 1 because projective TSDF overestimates the distance at grazing angles.
  double raycast_step_fraction = 0.8;

  void bind(OptionBinder& b) {
    // 8191 MiB: what the pool's 32-bit voxel index addresses (VoxelPool::kMaxSlots); the device
    // may allow less (checked when the pool is allocated).
    b.integer("memory_mb", memory_mb, 1, 8191, "MiB", "voxel-block pool budget, all volumes");
    b.real("background_voxel_m", background_voxel_m, 0.001, 0.5, "m", "background voxel size");
    // 4096: a grid of 512^3 blocks, the most a volume's index grid holds (2^27 blocks).
    b.integer("background_resolution", background_resolution, 8, 4096, "voxels",
              "background extent per axis");
    b.real("truncation_voxels", truncation_voxels, 1.0, 100.0, "voxels", "TSDF truncation");
    b.real("max_weight", max_weight, 1.0, 127.0, "",
           "TSDF weight cap W_max of the background (storage limit 127; objects: "
           "objects.max_weight)");
    b.integer("integrate_every", integrate_every, 1, 8, "frames",
              "each background block of the band is integrated every n-th frame (1 = all)");
    b.integer("mark_stride", mark_stride, 1, 4, "px",
              "the background's band blocks are found from every n-th pixel in x and y");
    b.boolean("free_space_full_weight", free_space_full_weight,
              "integrate free space with weight 1 regardless of association");
    b.real("initial_camera_face_offset", initial_camera_face_offset, 0.0, 0.5, "extent",
           "camera offset from the volume centre along its view axis (0.5 = on a face)");
    b.boolean("follow_camera", follow_camera,
              "the background moves with the camera, meshing and freeing what it leaves");
    b.real("follow_trigger_m", follow_trigger_m, 0.0, 100.0, "m",
           "the background moves when the view's focus is this far off its centre");
    b.real("follow_outside_fraction", follow_outside_fraction, 0.0, 1.0, "",
           "... and more than this share of the last frame saw surface outside it");
    b.real("raycast_min_depth_m", raycast_min_depth_m, 0.0, 100.0, "m",
           "nearest camera z rendered by ray casting");
    b.real("raycast_max_depth_m", raycast_max_depth_m, 0.01, 1000.0, "m",
           "farthest camera z rendered by ray casting");
    b.real("raycast_step_fraction", raycast_step_fraction, 0.05, 1.0, "",
           "ray-casting step in front of surfaces as a fraction of psi (>= one voxel)");
  }
};

}  // namespace emf::map
