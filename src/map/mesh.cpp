#include "map/mesh.h"

#include <unistd.h>

#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unordered_map>

#include "common/error.h"

namespace emf::map {

namespace {

/// Cube topology: corners n = x + 2y + 4z; edge e joins corners kEdge[e][0] < kEdge[e][1],
/// which differ in bit kEdgeAxis[e].
struct CubeTopology {
  int edge[12][2];
  int edge_axis[12];
  int edge_of[8][8];
  int face[6][4];  // corners counter-clockwise seen from outside the cube

  CubeTopology() {
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
};

const CubeTopology& topology() {
  static const CubeTopology t;
  return t;
}

struct Crossing {
  int edge;
  bool entering;  // the counter-clockwise walk goes from outside (psi >= 0) to inside
};

/// Closed loops of crossing edges of one cube (max 4 loops of up to 12 edges). Returns the
/// number of loops; loop i has lengths[i] edges in loops[i]. simple[i] is false when two of the
/// loop's segments lie on the same cube face: a fan from one of its vertices could then put a
/// diagonal on that face, where the neighbouring cube may put the same one.
int cubeLoops(const float f[8], int loops[4][12], int lengths[4], bool simple[4]) {
  const CubeTopology& topo = topology();
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

struct VertexKey {
  int64_t operator()(const Eigen::Vector3i& v, int axis, const Eigen::Vector3i& n) const {
    return ((static_cast<int64_t>(v.z()) * n.y() + v.y()) * n.x() + v.x()) * 3 + axis;
  }
};

}  // namespace

Mesh extractMesh(const VolumeHostData& vol, const MeshOptions& options) {
  const CubeTopology& topo = topology();
  const VolumeHostView view = vol.view();
  const Eigen::Vector3i dims_voxels = vol.dims_blocks * kBlockSize;
  const float vs = vol.voxel_size_m;
  const int min_weight_q = static_cast<int>(std::ceil(options.min_weight * kWeightScale));
  Mesh mesh;
  std::unordered_map<int64_t, int> vertex_of_edge;
  std::vector<Eigen::Vector3f> face_normal_sum;

  auto corner = [&](const Eigen::Vector3i& v, float* psi) {
    const int64_t i = view.voxelIndex(v);
    if (i < 0) return false;
    const Voxel& vox = vol.voxels[static_cast<size_t>(i)];
    if (vox.weight_q <= 0 || vox.weight_q < min_weight_q) return false;
    *psi = vox.tsdf();
    return true;
  };

  for (size_t lin = 0; lin < vol.index.size(); ++lin) {
    if (vol.index[lin] < 0) continue;
    const Eigen::Vector3i base = blockCoords(vol.dims_blocks, static_cast<int>(lin)) * kBlockSize;
    for (int lz = 0; lz < kBlockSize; ++lz) {
      for (int ly = 0; ly < kBlockSize; ++ly) {
        for (int lx = 0; lx < kBlockSize; ++lx) {
          const Eigen::Vector3i v0 = base + Eigen::Vector3i(lx, ly, lz);
          float f[8];
          bool ok = true;
          int inside = 0;
          for (int n = 0; n < 8 && ok; ++n) {
            ok = corner(v0 + Eigen::Vector3i(n & 1, (n >> 1) & 1, (n >> 2) & 1), &f[n]);
            if (ok && f[n] < 0.0f) inside |= 1 << n;
          }
          if (!ok || inside == 0 || inside == 255) continue;
          if (options.skip_truncated_crossings) {
            bool truncated = false;
            for (const auto& e : topo.edge) {
              const float a = f[e[0]], b = f[e[1]];
              if ((a < 0.0f) != (b < 0.0f) && std::fabs(a) >= 0.999f && std::fabs(b) >= 0.999f) {
                truncated = true;
              }
            }
            if (truncated) continue;
          }
          if (options.foreground_only && view.count_index &&
              samplePfgReference(view, (v0.cast<float>() + Eigen::Vector3f::Ones()) * vs) <= 0.5f) {
            continue;
          }
          int loops[4][12];
          int lengths[4];
          bool simple[4];
          const int nloops = cubeLoops(f, loops, lengths, simple);
          for (int l = 0; l < nloops; ++l) {
            int ids[12];
            for (int k = 0; k < lengths[l]; ++k) {
              const int e = loops[l][k];
              const int c0 = topo.edge[e][0], c1 = topo.edge[e][1];
              const Eigen::Vector3i vlow =
                  v0 + Eigen::Vector3i(c0 & 1, (c0 >> 1) & 1, (c0 >> 2) & 1);
              const int axis = topo.edge_axis[e];
              const int64_t key = VertexKey()(vlow, axis, dims_voxels);
              auto it = vertex_of_edge.find(key);
              if (it == vertex_of_edge.end()) {
                const float t = f[c0] / (f[c0] - f[c1]);
                Eigen::Vector3f p = vlow.cast<float>() + Eigen::Vector3f::Constant(0.5f);
                p[axis] += t;
                it = vertex_of_edge.emplace(key, static_cast<int>(mesh.vertices.size())).first;
                mesh.vertices.push_back(p * vs);
                face_normal_sum.push_back(Eigen::Vector3f::Zero());
              }
              ids[k] = it->second;
            }
            auto add_triangle = [&](const Eigen::Vector3i& tri) {
              mesh.triangles.push_back(tri);
              const Eigen::Vector3f nrm = (mesh.vertices[tri[1]] - mesh.vertices[tri[0]])
                                              .cross(mesh.vertices[tri[2]] - mesh.vertices[tri[0]]);
              for (int c = 0; c < 3; ++c) face_normal_sum[tri[c]] += nrm;
            };
            if (simple[l]) {
              for (int k = 1; k + 1 < lengths[l]; ++k) {
                add_triangle(Eigen::Vector3i(ids[0], ids[k], ids[k + 1]));
              }
            } else {
              // Fan around a vertex at the loop's centroid, inside this cube only.
              Eigen::Vector3f centre = Eigen::Vector3f::Zero();
              for (int k = 0; k < lengths[l]; ++k) centre += mesh.vertices[ids[k]];
              const int c = static_cast<int>(mesh.vertices.size());
              mesh.vertices.push_back(centre / static_cast<float>(lengths[l]));
              face_normal_sum.push_back(Eigen::Vector3f::Zero());
              for (int k = 0; k < lengths[l]; ++k) {
                add_triangle(Eigen::Vector3i(c, ids[k], ids[(k + 1) % lengths[l]]));
              }
            }
          }
        }
      }
    }
  }
  // Normals: the SDF gradient where the trilinear field is available, else the area-weighted
  // normal of the adjacent triangles.
  mesh.normals.resize(mesh.vertices.size());
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    float psi = 0.f, w = 0.f;
    Eigen::Vector3f g;
    Eigen::Vector3f n = face_normal_sum[i];
    if (sampleSdfReference(view, mesh.vertices[i], &psi, &w, &g) && g.norm() > 0.f) n = g;
    const float len = n.norm();
    mesh.normals[i] = len > 0.f ? Eigen::Vector3f(n / len) : Eigen::Vector3f(0.f, 0.f, 1.f);
  }
  if (options.world_frame) {
    const Eigen::Matrix3f R = vol.T_world_volume.rotation().cast<float>();
    const Eigen::Vector3f t = vol.T_world_volume.translation().cast<float>();
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
      mesh.vertices[i] = R * mesh.vertices[i] + t;
      mesh.normals[i] = R * mesh.normals[i];
    }
  }
  return mesh;
}

// ---- PLY --------------------------------------------------------------------------------------

namespace {

void appendLe(std::string& out, const void* p, size_t n) {
  // Little-endian hosts only (x86-64, aarch64 in little-endian mode).
  out.append(static_cast<const char*>(p), n);
}

}  // namespace

void writePly(const std::string& path, const Mesh& mesh, bool binary) {
  namespace fs = std::filesystem;
  static_assert(sizeof(float) == 4 && sizeof(int32_t) == 4, "PLY float/int are 32-bit");
  std::ostringstream header;
  header << "ply\nformat " << (binary ? "binary_little_endian" : "ascii") << " 1.0\n"
         << "comment emf mesh: metres, normals point to the free side\n"
         << "element vertex " << mesh.vertices.size() << "\n"
         << "property float x\nproperty float y\nproperty float z\n"
         << "property float nx\nproperty float ny\nproperty float nz\n"
         << "element face " << mesh.triangles.size() << "\n"
         << "property list uchar int vertex_indices\nend_header\n";
  std::string body = header.str();
  if (binary) {
    body.reserve(body.size() + mesh.vertices.size() * 24 + mesh.triangles.size() * 13);
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
      const float v[6] = {mesh.vertices[i].x(), mesh.vertices[i].y(), mesh.vertices[i].z(),
                          mesh.normals[i].x(),  mesh.normals[i].y(),  mesh.normals[i].z()};
      appendLe(body, v, sizeof(v));
    }
    for (const Eigen::Vector3i& t : mesh.triangles) {
      const uint8_t n = 3;
      const int32_t idx[3] = {t.x(), t.y(), t.z()};
      appendLe(body, &n, 1);
      appendLe(body, idx, sizeof(idx));
    }
  } else {
    std::ostringstream os;
    os.imbue(std::locale::classic());
    os.precision(9);
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
      os << mesh.vertices[i].x() << ' ' << mesh.vertices[i].y() << ' ' << mesh.vertices[i].z()
         << ' ' << mesh.normals[i].x() << ' ' << mesh.normals[i].y() << ' ' << mesh.normals[i].z()
         << '\n';
    }
    for (const Eigen::Vector3i& t : mesh.triangles) {
      os << "3 " << t.x() << ' ' << t.y() << ' ' << t.z() << '\n';
    }
    body += os.str();
  }
  const fs::path target(path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  static std::atomic<int> counter{0};
  const fs::path tmp =
      dir / ("." + target.filename().string() + ".tmp-" +
             std::to_string(static_cast<long>(::getpid())) + "-" + std::to_string(counter++));
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) {
      throw IoError("cannot write mesh " + path + ": cannot create " + tmp.string() +
                    " (does the folder exist and is it writable?)");
    }
    out.write(body.data(), static_cast<std::streamsize>(body.size()));
    out.flush();
    if (!out) {
      std::error_code ec;
      fs::remove(tmp, ec);
      throw IoError("cannot write mesh " + path + ": write to " + tmp.string() +
                    " failed (disk full?)");
    }
  }
  std::error_code ec;
  fs::rename(tmp, target, ec);
  if (ec) {
    std::error_code ignored;  // keep the rename's error for the message
    fs::remove(tmp, ignored);
    throw IoError("cannot write mesh " + path + ": rename from " + tmp.string() +
                  " failed: " + ec.message());
  }
}

Mesh readPly(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot open PLY file " + path);
  auto fail = [&](const std::string& what) { throw IoError("PLY file " + path + ": " + what); };
  std::string line;
  std::getline(in, line);
  if (line != "ply") fail("does not start with 'ply'");
  bool binary = false;
  size_t nv = 0, nf = 0;
  int vertex_props = 0;
  std::string element;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string word;
    ls >> word;
    if (word == "format") {
      std::string fmt;
      ls >> fmt;
      if (fmt == "binary_little_endian") {
        binary = true;
      } else if (fmt != "ascii") {
        fail("unsupported format '" + fmt + "'");
      }
    } else if (word == "element") {
      size_t n = 0;
      ls >> element >> n;
      if (element == "vertex") nv = n;
      if (element == "face") nf = n;
    } else if (word == "property" && element == "vertex") {
      ++vertex_props;
    } else if (word == "end_header") {
      break;
    }
  }
  if (vertex_props != 6) fail("expected 6 float vertex properties (x y z nx ny nz)");
  Mesh m;
  m.vertices.resize(nv);
  m.normals.resize(nv);
  m.triangles.resize(nf);
  for (size_t i = 0; i < nv; ++i) {
    float v[6];
    if (binary) {
      in.read(reinterpret_cast<char*>(v), sizeof(v));
    } else {
      for (float& x : v) in >> x;
    }
    if (!in) fail("truncated vertex list at vertex " + std::to_string(i));
    m.vertices[i] = Eigen::Vector3f(v[0], v[1], v[2]);
    m.normals[i] = Eigen::Vector3f(v[3], v[4], v[5]);
  }
  for (size_t i = 0; i < nf; ++i) {
    int32_t idx[3];
    if (binary) {
      uint8_t n = 0;
      in.read(reinterpret_cast<char*>(&n), 1);
      if (n != 3) fail("face " + std::to_string(i) + " is not a triangle");
      in.read(reinterpret_cast<char*>(idx), sizeof(idx));
    } else {
      int n = 0;
      in >> n;
      if (n != 3) fail("face " + std::to_string(i) + " is not a triangle");
      in >> idx[0] >> idx[1] >> idx[2];
    }
    if (!in) fail("truncated face list at face " + std::to_string(i));
    for (int c = 0; c < 3; ++c) {
      if (idx[c] < 0 || static_cast<size_t>(idx[c]) >= nv) {
        fail("face " + std::to_string(i) + " indexes vertex " + std::to_string(idx[c]) + " of " +
             std::to_string(nv));
      }
    }
    m.triangles[i] = Eigen::Vector3i(idx[0], idx[1], idx[2]);
  }
  return m;
}

}  // namespace emf::map
