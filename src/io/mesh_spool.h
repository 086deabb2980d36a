// A mesh kept on disk while it grows: the surface a moving background leaves behind
// (map/volume_follow.h), appended in parts during a run and streamed into every background
// mesh written (pipeline::SlamSystem::extractBackgroundMesh). Vertices (6 floats: position,
// normal) and triangles (3 int32, indices over all parts) go to two temporary files in a
// folder, unlinked at once so that nothing is left behind even after a crash. Memory: one batch.
#pragma once

#include <cstdio>
#include <string>

#include "map/mesh.h"

namespace emf::io {

class MeshSpool : public map::MeshSink {
 public:
  /// Creates the temporary files in `folder`. Throws IoError naming it when it cannot.
  explicit MeshSpool(const std::string& folder);
  ~MeshSpool() override;
  MeshSpool(const MeshSpool&) = delete;
  MeshSpool& operator=(const MeshSpool&) = delete;

  /// Starts a part: the triangles that follow index the vertices added from here on, from 0
  /// (as map::extractMesh gives them).
  void beginPart() { part_base_ = vertices_; }
  void addVertices(const Eigen::Vector3f* positions, const Eigen::Vector3f* normals,
                   size_t count) override;
  void addTriangles(const Eigen::Vector3i* triangles, size_t count) override;

  /// Streams every part to `sink` (vertices first, then triangles, indices from 0 over all
  /// parts); the spool keeps them. Throws IoError when the files cannot be read back.
  void replay(map::MeshSink& sink) const;

  size_t vertexCount() const { return vertices_; }
  size_t triangleCount() const { return triangles_; }

 private:
  std::FILE* open(const std::string& folder, const char* part);
  void write(std::FILE* f, const void* data, size_t bytes);

  std::FILE* vertex_file_ = nullptr;
  std::FILE* triangle_file_ = nullptr;
  std::string folder_;
  size_t vertices_ = 0, triangles_ = 0, part_base_ = 0;
};

}  // namespace emf::io
