// Mesh extraction from a volume (marching cubes on the host); PLY files are in io/ply.h.
//
// Marching cubes here builds each cube's polygons directly from the corner signs instead of the
// classic 256-case tables: on every cube face the iso-line segments are found by walking the face
// counter-clockwise (seen from outside), each segment running from the crossing where the walk
// enters the inside (psi < 0) to the crossing where it leaves, so that the inside is on its
// right; a face with 4 crossings is resolved by the sign of its centre value (mean of its corners),
// which both cubes sharing the face see alike, so the surface is watertight. The segments chain
// into closed loops (each crossing ends one face's segment and starts the other's), which are
// fan-triangulated counter-clockwise around the normal that points to the free side (psi > 0).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "map/volume.h"

namespace emf::map {

struct Mesh {
  std::vector<Eigen::Vector3f> vertices;   // metres, in the frame extraction was asked for
  std::vector<Eigen::Vector3f> normals;    // unit, pointing to the free side (psi > 0)
  std::vector<Eigen::Vector3i> triangles;  // counter-clockwise seen from the free side
};

struct MeshOptions {
  /// Vertices in the world frame (T_world_volume applied), else in the volume frame.
  bool world_frame = true;
  /// A cube is meshed only when all 8 corners are observed with at least this weight.
  float min_weight = 0.0f;
  /// Skip crossings between two truncated values (+-1 on both ends: a sign flip across
  /// unobserved space, not a measured surface).
  bool skip_truncated_crossings = true;
  /// Volumes with counts: mesh only cubes whose centre has p_fg > 0.5 (the object's voxels).
  bool foreground_only = true;
  /// When set, only the cubes with at least one corner outside this box of voxel coordinates
  /// (volume frame; min included, max excluded) are meshed: the surface that a shift of the
  /// grid takes out of it (map/volume_follow.h), seams to the staying blocks included.
  struct VoxelBox {
    Eigen::Vector3i min, max;
  };
  std::optional<VoxelBox> leaving;
};

/// Receives a mesh in pieces: vertices with consecutive indices from 0 in the order given,
/// triangles (indices into them) once their vertices have been given.
class MeshSink {
 public:
  virtual ~MeshSink() = default;
  virtual void addVertices(const Eigen::Vector3f* positions, const Eigen::Vector3f* normals,
                           size_t count) = 0;
  virtual void addTriangles(const Eigen::Vector3i* triangles, size_t count) = 0;
};

/// Marching cubes over all allocated blocks of the volume `view` shows (cubes across block
/// borders included), streamed to `sink` one z-layer of blocks at a time: the extraction holds
/// the vertices of about two block layers, not the mesh. Vertices come in z-major order of
/// their cube edge. `T_world_volume` is applied when options.world_frame is set.
void extractMesh(const VolumeHostView& view, const Eigen::Isometry3d& T_world_volume,
                 const MeshOptions& options, MeshSink& sink);
/// The same, collected in memory.
Mesh extractMesh(const VolumeHostView& view, const Eigen::Isometry3d& T_world_volume,
                 const MeshOptions& options = MeshOptions());
Mesh extractMesh(const VolumeHostData& vol, const MeshOptions& options = MeshOptions());

}  // namespace emf::map
