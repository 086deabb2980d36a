// Mesh extraction from a volume (marching cubes on the host) and PLY files.
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
};

/// Marching cubes over all allocated blocks of `vol` (cubes across block borders included).
Mesh extractMesh(const VolumeHostData& vol, const MeshOptions& options = MeshOptions());

/// Writes `mesh` as PLY (binary little-endian or ASCII) with vertex normals, atomically: to a
/// temporary file in the same folder, then renamed over `path`. Throws IoError naming the file.
void writePly(const std::string& path, const Mesh& mesh, bool binary);

/// Reads a PLY file written by writePly (either format). Throws IoError naming the file and
/// what is wrong.
Mesh readPly(const std::string& path);

}  // namespace emf::map
