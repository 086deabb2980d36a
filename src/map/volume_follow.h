// A background that follows the camera (docs/architecture.md#a-map-that-follows-the-camera):
// its grid moves by whole blocks so that the point the camera looks at stays near the grid's
// centre, in the same fixed pool (Volume::shift: re-indexed, nothing copied or allocated).
// What leaves the grid is meshed first (extractLeavingMesh), so its surface is kept.
//
// Frames: volume frame V (grid corner origin, axes along the grid), world W, camera C (z
// forward). Distances in metres.
#pragma once

#include <Eigen/Geometry>

#include "map/map_options.h"
#include "map/mesh.h"
#include "map/volume.h"

namespace emf::map {

/// When and how far the background moves.
struct FollowRule {
  /// The focus point, this far ahead of the camera along its view axis, is kept near the centre.
  double focus_m = 2.56;
  /// The grid moves when the focus is farther than this (at least one block) from its centre
  /// along a grid axis.
  double trigger_m = 1.0;
};

/// The rule of `options` for a background of `spec`: the focus is where the first camera sees
/// the grid centre (map.initial_camera_face_offset times the extent), the trigger
/// map.follow_trigger_m.
FollowRule followRule(const MapOptions& options, const VolumeSpec& spec);

/// The most a grid moves per frame along an axis, in blocks: a fast turn swings the focus by
/// metres, and the grid then catches up over a few frames instead of meshing a thick slab on
/// one.
constexpr int kMaxFollowStepBlocks = 2;

/// The move, in whole blocks along the grid axes, that brings the focus of a camera at
/// T_world_camera back within rule.trigger_m of the grid centre: per axis, the excess over the
/// trigger rounded up to whole blocks (at most kMaxFollowStepBlocks), zero where it is within.
Eigen::Vector3i followShift(const VolumeSpec& spec, const Eigen::Isometry3d& T_world_volume,
                            const Eigen::Isometry3d& T_world_camera, const FollowRule& rule);

/// The blocks whose voxels the mesh of what a shift by `blocks` takes out of a grid of `dims`
/// reads: those that leave and the layer of staying blocks next to them (a cube reads the
/// voxels of its block and of the next one along each axis).
Volume::BlockFilter leavingMeshBlocks(const Eigen::Vector3i& blocks, const Eigen::Vector3i& dims);

/// Meshes, in the world frame, the surface that volume.shift(blocks) takes out of the grid:
/// every cube with a corner in a leaving block (so the seam to the staying blocks goes with it,
/// and no later mesh of the grid repeats it). Maps the volume on CPU devices; elsewhere, or
/// with `force_download` (tests), it downloads only the leavingMeshBlocks().
void extractLeavingMesh(const Volume& volume, const Eigen::Vector3i& blocks, MeshSink& sink,
                        bool force_download = false);
/// The same from a host view of the volume before the shift (e.g. Volume::download of
/// leavingMeshBlocks(), meshed on another thread).
void extractLeavingMesh(const VolumeHostView& view, const Eigen::Isometry3d& T_world_volume,
                        const Eigen::Vector3i& blocks, MeshSink& sink);

}  // namespace emf::map
