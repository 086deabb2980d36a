// The polygons of one marching cube (see map/mesh.h for the method): corner and edge
// numbering, and the closed loops of crossing edges that a cube's corner signs give. Shared by
// the mesh extraction and its CPU reference in the tests.
#pragma once

namespace emf::map {

/// Cube topology: corners n = x + 2y + 4z; edge e joins corners edge[e][0] < edge[e][1],
/// which differ in bit edge_axis[e].
struct CubeTopology {
  int edge[12][2];
  int edge_axis[12];
  int edge_of[8][8];
  int face[6][4];  // corners counter-clockwise seen from outside the cube

  CubeTopology();
};

/// The one topology table.
const CubeTopology& cubeTopology();

/// Closed loops of crossing edges of one cube (max 4 loops of up to 12 edges). Returns the
/// number of loops; loop i has lengths[i] edges in loops[i]. simple[i] is false when two of the
/// loop's segments lie on the same cube face: a fan from one of its vertices could then put a
/// diagonal on that face, where the neighbouring cube may put the same one.
int cubeLoops(const float f[8], int loops[4][12], int lengths[4], bool simple[4]);

}  // namespace emf::map
