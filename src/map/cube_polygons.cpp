#include "map/cube_polygons.h"

namespace emf::map {

namespace {

struct Crossing {
  int edge;
  bool entering;  // the counter-clockwise walk goes from outside (psi >= 0) to inside
};

}  // namespace

CubeTopology::CubeTopology() {
  for (auto& row : edge_of) {
    for (int& e : row) e = -1;
  }
  int e = 0;
  for (int a = 0; a < 3; ++a) {
    for (int c = 0; c < 8; ++c) {
      if (c & (1 << a)) continue;
      edge[e][0] = c;
      edge[e][1] = c | (1 << a);
      edge_axis[e] = a;
      edge_of[c][c | (1 << a)] = e;
      edge_of[c | (1 << a)][c] = e;
      ++e;
    }
  }
  // Face normal +-e_a; (u, w, a) is a cyclic permutation, so e_u x e_w = e_a and the walk
  // (0,0) (1,0) (1,1) (0,1) in (u, w) turns counter-clockwise around +e_a.
  static const int kCcw[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  int f = 0;
  for (int a = 0; a < 3; ++a) {
    const int u = (a + 1) % 3, w = (a + 2) % 3;
    for (int s = 0; s < 2; ++s) {
      for (int i = 0; i < 4; ++i) {
        // Outward -e_a (s = 0) walks the other way round.
        const int k = s == 1 ? i : (4 - i) % 4;
        face[f][i] = (s << a) | (kCcw[k][0] << u) | (kCcw[k][1] << w);
      }
      ++f;
    }
  }
}

const CubeTopology& cubeTopology() {
  static const CubeTopology t;
  return t;
}

int cubeLoops(const float f[8], int loops[4][12], int lengths[4], bool simple[4]) {
  const CubeTopology& topo = cubeTopology();
  int next[12];
  int segment_face[12];
  for (int& n : next) n = -1;
  for (int fi = 0; fi < 6; ++fi) {
    const auto& face = topo.face[fi];
    Crossing x[4];
    int nx = 0;
    for (int i = 0; i < 4; ++i) {
      const int a = face[i], b = face[(i + 1) % 4];
      const bool in_a = f[a] < 0.0f, in_b = f[b] < 0.0f;
      if (in_a != in_b) x[nx++] = Crossing{topo.edge_of[a][b], in_b};
    }
    if (nx == 2) {
      const Crossing& en = x[0].entering ? x[0] : x[1];
      const Crossing& le = x[0].entering ? x[1] : x[0];
      next[en.edge] = le.edge;
      segment_face[en.edge] = fi;
    } else if (nx == 4) {
      // Inside corners joined through the face centre when its (bilinear) value is inside.
      const float centre = 0.25f * (f[face[0]] + f[face[1]] + f[face[2]] + f[face[3]]);
      const bool inside_connected = centre < 0.0f;
      for (int i = 0; i < 4; ++i) {
        if (!x[i].entering) continue;
        const int j = inside_connected ? (i + 3) % 4 : (i + 1) % 4;
        next[x[i].edge] = x[j].edge;
        segment_face[x[i].edge] = fi;
      }
    }
  }
  bool used[12] = {false};
  int count = 0;
  for (int start = 0; start < 12 && count < 4; ++start) {
    if (next[start] < 0 || used[start]) continue;
    int len = 0;
    int e = start;
    bool closed = false;
    int faces_seen = 0;
    simple[count] = true;
    while (len < 12 && e >= 0 && !used[e]) {
      used[e] = true;
      if (faces_seen & (1 << segment_face[e])) simple[count] = false;
      faces_seen |= 1 << segment_face[e];
      loops[count][len++] = e;
      e = next[e];
      if (e == start) {
        closed = true;
        break;
      }
    }
    if (closed && len >= 3) lengths[count++] = len;
  }
  return count;
}

}  // namespace emf::map
