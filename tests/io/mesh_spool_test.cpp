// io::MeshSpool: parts appended with their own vertex numbering come back as one mesh with
// indices over all parts, leave no file behind, and a folder that cannot hold them is named.
#include "io/mesh_spool.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "common/error.h"
#include "test_support.h"

namespace emf::test {
namespace {

struct Collect : map::MeshSink {
  map::Mesh m;
  void addVertices(const Eigen::Vector3f* p, const Eigen::Vector3f* n, size_t c) override {
    m.vertices.insert(m.vertices.end(), p, p + c);
    m.normals.insert(m.normals.end(), n, n + c);
  }
  void addTriangles(const Eigen::Vector3i* t, size_t c) override {
    m.triangles.insert(m.triangles.end(), t, t + c);
  }
};

/// One part: `n` vertices at x = first + i, triangles (0, 1, 2), (1, 2, 3), ... of the part.
void addPart(io::MeshSpool& spool, int first, int n) {
  spool.beginPart();
  std::vector<Eigen::Vector3f> p, nrm;
  for (int i = 0; i < n; ++i) {
    p.emplace_back(static_cast<float>(first + i), 0.5f, -1.0f);
    nrm.emplace_back(0.0f, 0.0f, 1.0f);
  }
  spool.addVertices(p.data(), nrm.data(), p.size());
  std::vector<Eigen::Vector3i> t;
  for (int i = 0; i + 2 < n; ++i) t.emplace_back(i, i + 1, i + 2);
  spool.addTriangles(t.data(), t.size());
}

TEST(MeshSpool, PartsComeBackAsOneMeshWithIndicesOverAllParts) {
  const std::string dir = tempDir("mesh_spool");
  Collect out;
  {
    io::MeshSpool spool(dir);
    addPart(spool, 0, 4);
    addPart(spool, 100, 70000);  // more than one read-back batch
    EXPECT_EQ(spool.vertexCount(), 70004u);
    EXPECT_EQ(spool.triangleCount(), 2u + 69998u);
    spool.replay(out);
    // Appending goes on after a replay, and a second replay gives the third part too.
    addPart(spool, 500, 3);
    Collect again;
    spool.replay(again);
    EXPECT_EQ(again.m.vertices.size(), 70007u);
    ASSERT_EQ(again.m.triangles.size(), 70001u);
    EXPECT_EQ(again.m.triangles.back(), Eigen::Vector3i(70004, 70005, 70006));
    EXPECT_EQ(again.m.vertices.back(), Eigen::Vector3f(502.0f, 0.5f, -1.0f));
  }
  ASSERT_EQ(out.m.vertices.size(), 70004u);
  EXPECT_EQ(out.m.vertices[3], Eigen::Vector3f(3.0f, 0.5f, -1.0f));
  EXPECT_EQ(out.m.vertices[4], Eigen::Vector3f(100.0f, 0.5f, -1.0f));
  EXPECT_EQ(out.m.normals[70003], Eigen::Vector3f(0.0f, 0.0f, 1.0f));
  ASSERT_EQ(out.m.triangles.size(), 70000u);
  EXPECT_EQ(out.m.triangles[1], Eigen::Vector3i(1, 2, 3));
  EXPECT_EQ(out.m.triangles[2], Eigen::Vector3i(4, 5, 6));  // the second part, offset by 4
  // Its files were unlinked when created: the folder is empty.
  EXPECT_TRUE(std::filesystem::is_empty(dir));
}

TEST(MeshSpool, AFolderThatCannotHoldItIsNamed) {
  const std::string missing = tempDir("mesh_spool_missing") + "/no/such/folder";
  try {
    io::MeshSpool spool(missing);
    FAIL() << "no error";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace emf::test
