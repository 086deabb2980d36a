// PLY files of meshes: x y z nx ny nz float vertices and uchar-int triangle lists, binary
// little-endian or ASCII. Written atomically and, through PlyWriter, streamed: a mesh extracted
// straight into a PlyWriter is never held in memory as a whole.
#pragma once

#include <cstdio>
#include <memory>
#include <string>

#include "io/atomic_output.h"
#include "map/mesh.h"

namespace emf::io {

/// A PLY file being written from a stream of vertices and triangles (a MeshSink). Vertices go
/// straight into the temporary file of an AtomicOutputFile behind a reserved header; triangles
/// into a second, already unlinked temporary file next to it (so nothing is left behind even on a
/// crash); commit() appends the triangles, writes the header with the final counts (padded to
/// the reserved size by a comment line), fsyncs and renames over `path`. Disk: the PLY plus its
/// triangles once more. Destroying it without commit() leaves `path` untouched and no files.
class PlyWriter : public map::MeshSink {
 public:
  /// Throws IoError naming `path` when the temporary files cannot be created there.
  PlyWriter(std::string path, bool binary);
  ~PlyWriter() override;
  PlyWriter(const PlyWriter&) = delete;
  PlyWriter& operator=(const PlyWriter&) = delete;

  void addVertices(const Eigen::Vector3f* positions, const Eigen::Vector3f* normals,
                   size_t count) override;
  void addTriangles(const Eigen::Vector3i* triangles, size_t count) override;
  /// Throws IoError naming the file (disk full, rename failed, ...).
  void commit();

  size_t vertexCount() const { return vertices_; }
  size_t triangleCount() const { return triangles_; }

 private:
  class FacePart;
  std::string path_;
  bool binary_;
  std::unique_ptr<AtomicOutputFile> out_;
  std::unique_ptr<FacePart> faces_;
  size_t vertices_ = 0, triangles_ = 0;
  std::string buffer_;  // one batch, encoded
};

/// Writes `mesh` as PLY (binary little-endian or ASCII) with vertex normals, atomically.
/// Throws IoError naming the file.
void writePly(const std::string& path, const map::Mesh& mesh, bool binary);

/// Reads a PLY file written by writePly / PlyWriter (either format). Throws IoError naming the
/// file and what is wrong.
map::Mesh readPly(const std::string& path);

}  // namespace emf::io
