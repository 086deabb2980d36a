// Marching cubes on host volumes filled with analytic / random SDFs: accuracy, orientation,
// watertightness (ambiguous faces included); PLY binary and ASCII; point-to-mesh distance.
#include "map/mesh.h"

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <locale>
#include <map>
#include <random>

#include "common/error.h"
#include "io/ply.h"
#include "map/mesh_distance.h"
#include "mesh_reference.h"
#include "test_support.h"

namespace emf::test {
namespace {

/// A host volume of dims blocks, every block allocated, psi(v) from f(voxel centre, metres).
template <typename F>
map::VolumeHostData filledVolume(const Eigen::Vector3i& dims, float voxel, float truncation, F f) {
  map::VolumeHostData h;
  h.dims_blocks = dims;
  h.voxel_size_m = voxel;
  h.truncation_m = truncation;
  const int n = dims.prod();
  h.index.resize(static_cast<size_t>(n));
  h.voxels.resize(static_cast<size_t>(n) * map::kBlockVoxels);
  for (int lin = 0; lin < n; ++lin) {
    h.index[static_cast<size_t>(lin)] = lin;
    const Eigen::Vector3i base = map::blockCoords(dims, lin) * map::kBlockSize;
    for (int i = 0; i < map::kBlockVoxels; ++i) {
      const Eigen::Vector3i v = base + Eigen::Vector3i(i % 8, (i / 8) % 8, i / 64);
      const Eigen::Vector3f p = (v.cast<float>() + Eigen::Vector3f::Constant(0.5f)) * voxel;
      h.voxels[static_cast<size_t>(lin) * map::kBlockVoxels + i] =
          map::Voxel::make(f(p, v) / truncation, 1.0f);
    }
  }
  return h;
}

/// Each undirected edge is used by exactly two triangles, once in each direction (closed,
/// consistently oriented surface).
void expectClosedAndOriented(const map::Mesh& m) {
  std::map<std::pair<int, int>, int> directed;
  for (const Eigen::Vector3i& t : m.triangles) {
    for (int c = 0; c < 3; ++c) directed[{t[c], t[(c + 1) % 3]}]++;
  }
  int bad = 0;
  for (const auto& [e, count] : directed) {
    const auto rev = directed.find({e.second, e.first});
    if (count != 1 || rev == directed.end() || rev->second != 1) {
      if (bad++ < 5) ADD_FAILURE() << "edge " << e.first << "-" << e.second << " used " << count;
    }
  }
  EXPECT_EQ(bad, 0);
}

TEST(Mesh, SphereIsAccurateClosedAndFacesOutward) {
  const Eigen::Vector3f c(0.16f, 0.17f, 0.15f);
  const float r = 0.1f, voxel = 0.01f;
  const map::VolumeHostData h = filledVolume(
      Eigen::Vector3i(4, 4, 4), voxel, 0.05f,
      [&](const Eigen::Vector3f& p, const Eigen::Vector3i&) { return (p - c).norm() - r; });
  map::MeshOptions opt;
  opt.world_frame = false;
  const map::Mesh m = map::extractMesh(h, opt);
  ASSERT_GT(m.triangles.size(), 1000u);
  float max_err = 0;
  for (size_t i = 0; i < m.vertices.size(); ++i) {
    max_err = std::max(max_err, std::abs((m.vertices[i] - c).norm() - r));
    EXPECT_GT(m.normals[i].dot((m.vertices[i] - c).normalized()), 0.99f) << i;
  }
  // Linear interpolation of the exact SDF along voxel edges: error well below a tenth of a voxel.
  EXPECT_LT(max_err, 0.05f * voxel);
  for (const Eigen::Vector3i& t : m.triangles) {
    const Eigen::Vector3f n =
        (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]);
    const Eigen::Vector3f centre = (m.vertices[t[0]] + m.vertices[t[1]] + m.vertices[t[2]]) / 3;
    if (n.norm() > 1e-12f) {
      EXPECT_GT(n.dot(centre - c), 0.f) << "triangle faces inward";
    }
  }
  expectClosedAndOriented(m);
  // Euler characteristic of a sphere: V - E + F = 2.
  const long v = static_cast<long>(m.vertices.size()), f = static_cast<long>(m.triangles.size());
  EXPECT_EQ(v - 3 * f / 2 + f, 2);
}

TEST(Mesh, RandomFieldsWithAmbiguousFacesAreWatertight) {
  // Random signs inside, positive border: many ambiguous faces and cubes; the surface must be
  // closed and consistently oriented everywhere.
  for (int seed = 0; seed < 5; ++seed) {
    std::mt19937 rng(static_cast<unsigned>(seed));
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    const map::VolumeHostData h =
        filledVolume(Eigen::Vector3i(2, 2, 2), 0.01f, 0.05f,
                     [&](const Eigen::Vector3f&, const Eigen::Vector3i& v) {
                       const bool border = (v.array() == 0).any() || (v.array() == 15).any();
                       return border ? 0.04f : 0.04f * u(rng);
                     });
    const map::Mesh m = map::extractMesh(h);
    ASSERT_GT(m.triangles.size(), 100u);
    expectClosedAndOriented(m);
  }
}

TEST(Mesh, BlockBordersAndUnobservedVoxels) {
  // A plane crossing block borders; voxels beyond x = 10 unobserved: no cube touching them is
  // meshed, everything else is.
  const map::VolumeHostData full =
      filledVolume(Eigen::Vector3i(3, 3, 3), 0.01f, 0.05f,
                   [](const Eigen::Vector3f& p, const Eigen::Vector3i&) { return p.z() - 0.123f; });
  map::VolumeHostData h = full;
  for (size_t lin = 0; lin < h.index.size(); ++lin) {
    const Eigen::Vector3i base = map::blockCoords(h.dims_blocks, static_cast<int>(lin)) * 8;
    for (int i = 0; i < map::kBlockVoxels; ++i) {
      if (base.x() + i % 8 > 10) h.voxels[lin * map::kBlockVoxels + static_cast<size_t>(i)] = {};
    }
  }
  map::MeshOptions opt;
  opt.world_frame = false;
  const map::Mesh m = map::extractMesh(h, opt);
  // Cubes with lower corner x in [0, 9] (corner x+1 <= 10) and y in [0, 22]: 10 x 23 quads.
  EXPECT_EQ(m.triangles.size(), 10u * 23u * 2u);
  for (const auto& p : m.vertices) {
    EXPECT_NEAR(p.z(), 0.123f, 1e-4f);
    EXPECT_LE(p.x(), 0.1051f);
  }
  const map::Mesh all = map::extractMesh(full, opt);
  EXPECT_EQ(all.triangles.size(), 23u * 23u * 2u);
}

TEST(Mesh, PlyBinaryAndAsciiRoundTripAtomically) {
  const map::VolumeHostData h = filledVolume(
      Eigen::Vector3i(2, 2, 2), 0.01f, 0.05f, [](const Eigen::Vector3f& p, const Eigen::Vector3i&) {
        return (p - Eigen::Vector3f(0.08f, 0.08f, 0.08f)).norm() - 0.05f;
      });
  map::VolumeHostData moved = h;
  moved.T_world_volume.translation() = Eigen::Vector3d(1, 2, 3);
  const map::Mesh m = map::extractMesh(moved);
  EXPECT_NEAR(m.vertices[0].z(), 3.08f, 0.06f);  // world frame applied
  const std::string dir = tempDir("ply");
  for (bool binary : {true, false}) {
    const std::string path = dir + (binary ? "/m_bin.ply" : "/m_ascii.ply");
    io::writePly(path, m, binary);
    std::ifstream in(path);
    std::string l1, l2;
    std::getline(in, l1);
    std::getline(in, l2);
    EXPECT_EQ(l1, "ply");
    EXPECT_EQ(l2, binary ? "format binary_little_endian 1.0" : "format ascii 1.0");
    const map::Mesh r = io::readPly(path);
    ASSERT_EQ(r.vertices.size(), m.vertices.size());
    ASSERT_EQ(r.triangles.size(), m.triangles.size());
    const float tol = binary ? 0.f : 1e-6f;
    for (size_t i = 0; i < m.vertices.size(); ++i) {
      ASSERT_LE((r.vertices[i] - m.vertices[i]).cwiseAbs().maxCoeff(), tol);
      ASSERT_LE((r.normals[i] - m.normals[i]).cwiseAbs().maxCoeff(), tol);
    }
    EXPECT_EQ(r.triangles, m.triangles);
  }
  // Only the two outputs: no temporary files left behind.
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    ++files;
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos);
  }
  EXPECT_EQ(files, 2);
  // Unwritable target: IoError naming the file.
  try {
    io::writePly(dir + "/no/such/folder/m.ply", m, true);
    FAIL() << "expected IoError";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("no/such/folder/m.ply"), std::string::npos) << e.what();
  }
  // A target that is a folder: the rename's own error, not the clean-up's "Success".
  std::filesystem::create_directories(dir + "/a_folder.ply");
  try {
    io::writePly(dir + "/a_folder.ply", m, true);
    FAIL() << "expected IoError";
  } catch (const IoError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("a_folder.ply"), std::string::npos) << what;
    EXPECT_NE(what.find("Is a directory"), std::string::npos) << what;
    EXPECT_EQ(what.find("Success"), std::string::npos) << what;
  }
  std::filesystem::remove(dir + "/a_folder.ply");
  // A truncated file is reported, not crashed on.
  {
    std::ofstream(dir + "/bad.ply") << "ply\nformat ascii 1.0\nelement vertex 5\n"
                                       "property float x\nproperty float y\nproperty float z\n"
                                       "property float nx\nproperty float ny\nproperty float nz\n"
                                       "element face 0\nend_header\n1 2 3 0 0 1\n";
  }
  EXPECT_THROW(io::readPly(dir + "/bad.ply"), IoError);
}

TEST(Mesh, StreamedPlyEqualsTheMeshInMemoryAcrossBlockLayers) {
  // A sphere spanning four z-layers of blocks, the third layer unallocated (the walk jumps a
  // layer): the streamed file holds exactly the in-memory mesh, closed where the layers are.
  const Eigen::Vector3f c(0.16f, 0.16f, 0.16f);
  map::VolumeHostData h = filledVolume(
      Eigen::Vector3i(4, 4, 4), 0.01f, 0.05f,
      [&](const Eigen::Vector3f& p, const Eigen::Vector3i&) { return (p - c).norm() - 0.13f; });
  const map::Mesh whole = map::extractMesh(h);
  expectClosedAndOriented(whole);
  for (size_t lin = 0; lin < h.index.size(); ++lin) {
    if (map::blockCoords(h.dims_blocks, static_cast<int>(lin)).z() == 2) h.index[lin] = -1;
  }
  h.T_world_volume.translation() = Eigen::Vector3d(-1, 0.5, 2);
  const map::Mesh m = map::extractMesh(h);
  ASSERT_GT(m.triangles.size(), 1000u);
  ASSERT_LT(m.triangles.size(), whole.triangles.size());
  const std::string dir = tempDir("ply-stream");
  for (bool binary : {true, false}) {
    const std::string path = dir + (binary ? "/s_bin.ply" : "/s_ascii.ply");
    io::PlyWriter writer(path, binary);
    map::extractMesh(h.view(), h.T_world_volume, map::MeshOptions(), writer);
    EXPECT_EQ(writer.vertexCount(), m.vertices.size());
    EXPECT_EQ(writer.triangleCount(), m.triangles.size());
    writer.commit();
    const map::Mesh r = io::readPly(path);
    ASSERT_EQ(r.vertices.size(), m.vertices.size());
    const float tol = binary ? 0.f : 1e-6f;
    for (size_t i = 0; i < m.vertices.size(); ++i) {
      ASSERT_LE((r.vertices[i] - m.vertices[i]).cwiseAbs().maxCoeff(), tol) << i;
      ASSERT_LE((r.normals[i] - m.normals[i]).cwiseAbs().maxCoeff(), tol) << i;
    }
    EXPECT_EQ(r.triangles, m.triangles);
  }
  // Vertices come in z-major order of their cube edge's lower voxel: a vertex lies at most one
  // voxel above that voxel's centre (a z edge, a loop's centre), so z never drops by more.
  for (size_t i = 1; i < m.vertices.size(); ++i) {
    ASSERT_GE(m.vertices[i].z() - m.vertices[i - 1].z(), -0.0101f) << i;
  }
  // A writer abandoned without commit() leaves nothing behind, not even its temporary files.
  {
    io::PlyWriter abandoned(dir + "/abandoned.ply", true);
    map::extractMesh(h.view(), h.T_world_volume, map::MeshOptions(), abandoned);
  }
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    ++files;
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
  }
  EXPECT_EQ(files, 2);
}

/// Triangles as their three vertices (position, normal), each started at its smallest vertex
/// (the winding kept), sorted: equal for equal meshes whatever the vertex order.
std::vector<std::array<float, 18>> canonicalTriangles(const map::Mesh& m) {
  std::vector<std::array<float, 18>> out;
  for (const Eigen::Vector3i& t : m.triangles) {
    std::array<std::array<float, 6>, 3> v;
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3f& p = m.vertices[static_cast<size_t>(t[c])];
      const Eigen::Vector3f& n = m.normals[static_cast<size_t>(t[c])];
      v[static_cast<size_t>(c)] = {p.x(), p.y(), p.z(), n.x(), n.y(), n.z()};
    }
    const size_t first = static_cast<size_t>(std::min_element(v.begin(), v.end()) - v.begin());
    std::array<float, 18> row;
    for (size_t c = 0; c < 3; ++c) {
      std::copy(v[(first + c) % 3].begin(), v[(first + c) % 3].end(), row.begin() + 6 * c);
    }
    out.push_back(row);
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(Mesh, StreamedExtractionEqualsTheNonStreamingReference) {
  // Random volumes: 1-4 blocks per axis, blocks missing (whole z-layers too), slots in random
  // order, smooth fields with noise, saturated (truncated) regions, unobserved voxels, counts
  // with foreground-only meshing, min_weight, random poses. The streamed extraction must give
  // the reference's triangles on the reference's vertices (positions and normals bit-equal).
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  size_t total_triangles = 0, with_counts = 0;
  for (int trial = 0; trial < 60; ++trial) {
    map::VolumeHostData h;
    h.dims_blocks = test::drawXyz<Eigen::Vector3i>([&] { return 1 + static_cast<int>(rng() % 4); });
    h.voxel_size_m = 0.01f;
    h.truncation_m = 0.04f;
    const int n = h.dims_blocks.prod();
    const bool counts = trial % 3 == 0;
    const int skipped_layer = u(rng) < 0.4f ? static_cast<int>(rng() % 4) : -1;
    std::vector<int> lins;
    for (int lin = 0; lin < n; ++lin) {
      if (map::blockCoords(h.dims_blocks, lin).z() == skipped_layer || u(rng) < 0.2f) continue;
      lins.push_back(lin);
    }
    std::vector<int> slots(lins.size() * (counts ? 2 : 1));
    for (size_t i = 0; i < slots.size(); ++i) slots[i] = static_cast<int>(i);
    std::shuffle(slots.begin(), slots.end(), rng);
    h.index.assign(static_cast<size_t>(n), -1);
    if (counts) h.count_index.assign(static_cast<size_t>(n), -1);
    h.voxels.resize(slots.size() * map::kBlockVoxels);
    // Field: three spheres of random centre and radius, noise, clamped to +-1 (truncation).
    Eigen::Vector3f centre[3];
    float radius[3];
    const Eigen::Vector3f ext = h.dims_blocks.cast<float>() * 0.08f;
    for (int k = 0; k < 3; ++k) {
      centre[k] = test::drawXyz<Eigen::Vector3f>([&] { return u(rng); }).cwiseProduct(ext);
      radius[k] = 0.02f + 0.1f * u(rng);
    }
    const float noise = trial % 2 ? 0.3f : 0.0f;
    for (size_t b = 0; b < lins.size(); ++b) {
      const int lin = lins[b];
      h.index[static_cast<size_t>(lin)] = slots[b];
      if (counts) h.count_index[static_cast<size_t>(lin)] = slots[lins.size() + b];
      const Eigen::Vector3i base = map::blockCoords(h.dims_blocks, lin) * map::kBlockSize;
      for (int i = 0; i < map::kBlockVoxels; ++i) {
        const Eigen::Vector3i v = base + Eigen::Vector3i(i % 8, (i / 8) % 8, i / 64);
        const Eigen::Vector3f p = (v.cast<float>() + Eigen::Vector3f::Constant(0.5f)) * 0.01f;
        float d = 1e9f;
        for (int k = 0; k < 3; ++k) d = std::min(d, (p - centre[k]).norm() - radius[k]);
        const float tsdf = std::clamp(d / h.truncation_m + noise * (u(rng) - 0.5f), -1.f, 1.f);
        const float weight = u(rng) < 0.03f ? 0.f : 1.f + 9.f * u(rng);
        h.voxels[static_cast<size_t>(slots[b]) * map::kBlockVoxels + static_cast<size_t>(i)] =
            map::Voxel::make(tsdf, weight);
        if (counts) {
          h.voxels[static_cast<size_t>(slots[lins.size() + b]) * map::kBlockVoxels +
                   static_cast<size_t>(i)] =
              map::addCounts(map::Voxel{}, p.x() < ext.x() / 2 ? 0.9f : 0.2f);
        }
      }
    }
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    // One draw per statement (test::drawXyz): the axis's y, its x, then the angle.
    const double axis_y = u(rng);
    const Eigen::Vector3d axis = Eigen::Vector3d(u(rng), axis_y, 1).normalized();
    T.linear() = Eigen::AngleAxisd(6.0 * u(rng), axis).toRotationMatrix();
    T.translation() = test::drawXyz<Eigen::Vector3d>([&] { return u(rng); });
    map::MeshOptions opt;
    opt.world_frame = trial % 4 != 1;
    opt.min_weight = trial % 5 == 2 ? 4.f : 0.f;
    opt.skip_truncated_crossings = trial % 7 != 3;
    const map::Mesh streamed = map::extractMesh(h.view(), T, opt);
    const map::Mesh reference = extractMeshReference(h.view(), T, opt);
    ASSERT_EQ(streamed.vertices.size(), reference.vertices.size()) << "trial " << trial;
    ASSERT_EQ(streamed.triangles.size(), reference.triangles.size()) << "trial " << trial;
    ASSERT_TRUE(canonicalTriangles(streamed) == canonicalTriangles(reference)) << "trial " << trial;
    total_triangles += streamed.triangles.size();
    with_counts += counts ? streamed.triangles.size() : 0;
  }
  EXPECT_GT(total_triangles, 30000u);  // 37500 with this seed
  EXPECT_GT(with_counts, 5000u) << with_counts;
}

TEST(Mesh, PlyIgnoresTheHostProgramsLocale) {
  // A host program with a global locale that groups digits ("1,234") must still get a PLY
  // header other programs (and readPly) can read.
  struct Grouping : std::numpunct<char> {
    char do_thousands_sep() const override { return ','; }
    std::string do_grouping() const override { return "\3"; }
  };
  const map::VolumeHostData h = filledVolume(
      Eigen::Vector3i(3, 3, 3), 0.01f, 0.05f, [](const Eigen::Vector3f& p, const Eigen::Vector3i&) {
        return (p - Eigen::Vector3f(0.12f, 0.12f, 0.12f)).norm() - 0.1f;
      });
  const map::Mesh m = map::extractMesh(h);
  ASSERT_GT(m.vertices.size(), 1000u);
  const std::string dir = tempDir("ply-locale");
  const std::locale before = std::locale::global(std::locale(std::locale::classic(), new Grouping));
  std::vector<map::Mesh> read;
  std::string header;
  try {
    for (bool binary : {true, false}) {
      const std::string path = dir + (binary ? "/g_bin.ply" : "/g_ascii.ply");
      io::writePly(path, m, binary);
      read.push_back(io::readPly(path));
      std::ifstream in(path);
      std::string line;
      while (std::getline(in, line) && line != "end_header") header += line + "\n";
    }
  } catch (...) {
    std::locale::global(before);
    throw;
  }
  std::locale::global(before);
  EXPECT_NE(header.find("element vertex " + std::to_string(m.vertices.size()) + "\n"),
            std::string::npos)
      << header;
  for (const map::Mesh& r : read) {
    ASSERT_EQ(r.vertices.size(), m.vertices.size());
    EXPECT_EQ(r.triangles, m.triangles);
  }
}

TEST(MeshDistanceTest, MatchesBruteForce) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(0.f, 0.3f);
  map::Mesh m;
  for (int i = 0; i < 300; ++i) {
    const Eigen::Vector3f a = test::drawXyz<Eigen::Vector3f>([&] { return u(rng); });
    const Eigen::Vector3f d1 = Eigen::Vector3f::Random() * 0.02f,
                          d2 = Eigen::Vector3f::Random() * 0.02f;
    m.vertices.push_back(a);
    m.vertices.push_back(a + d1);
    m.vertices.push_back(a + d2);
    m.triangles.emplace_back(3 * i, 3 * i + 1, 3 * i + 2);
  }
  m.normals.assign(m.vertices.size(), Eigen::Vector3f::UnitZ());
  const map::MeshDistance md(m, 0.02f);
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector3f p = test::drawXyz<Eigen::Vector3f>([&] { return u(rng); });
    float brute = std::numeric_limits<float>::infinity();
    for (const auto& t : m.triangles) {
      brute = std::min(brute, map::pointTriangleDistance(p, m.vertices[t[0]], m.vertices[t[1]],
                                                         m.vertices[t[2]]));
    }
    const float d = md.distance(p, 0.1f);
    if (brute <= 0.1f) {
      EXPECT_FLOAT_EQ(d, brute) << i;
    } else {
      EXPECT_GT(d, 0.1f);
    }
  }
  // Known distances: above the plane of a right triangle, beyond an edge and a corner.
  const Eigen::Vector3f a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_FLOAT_EQ(map::pointTriangleDistance({0.2f, 0.2f, 0.5f}, a, b, c), 0.5f);
  EXPECT_FLOAT_EQ(map::pointTriangleDistance({0.5f, -0.3f, 0.4f}, a, b, c), 0.5f);
  EXPECT_FLOAT_EQ(map::pointTriangleDistance({-0.3f, -0.4f, 0.0f}, a, b, c), 0.5f);
}

}  // namespace
}  // namespace emf::test
