// CPU reference of map::extractMesh without streaming: every cube of every allocated block, one
// hash map from cube edge to vertex for the whole volume, normals at the end (the extraction as
// it was before it streamed, 3a86a1c). The streamed extraction must give the same triangles on
// the same vertices, in another vertex order.
#pragma once

#include <Eigen/Geometry>

#include "map/mesh.h"

namespace emf::test {

map::Mesh extractMeshReference(const map::VolumeHostView& view,
                               const Eigen::Isometry3d& T_world_volume,
                               const map::MeshOptions& options);

}  // namespace emf::test
