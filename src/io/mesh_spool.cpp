#include "io/mesh_spool.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <vector>

#include "common/error.h"

namespace emf::io {

namespace {
constexpr size_t kBatch = 1 << 16;  // records read back at a time
}  // namespace

MeshSpool::MeshSpool(const std::string& folder) : folder_(folder) {
  vertex_file_ = open(folder, "vertices");
  try {
    triangle_file_ = open(folder, "triangles");
  } catch (...) {
    std::fclose(vertex_file_);
    throw;
  }
}

MeshSpool::~MeshSpool() {
  std::fclose(vertex_file_);
  std::fclose(triangle_file_);
}

std::FILE* MeshSpool::open(const std::string& folder, const char* part) {
  static std::atomic<int> counter{0};
  const std::string path = (std::filesystem::path(folder.empty() ? "." : folder) /
                            (".emf-evicted-" + std::to_string(static_cast<long>(::getpid())) + "-" +
                             std::to_string(counter++) + "-" + part))
                               .string();
  std::FILE* f = std::fopen(path.c_str(), "w+b");
  if (!f) {
    throw IoError("cannot keep the surface the moving map leaves: cannot create " + path + ": " +
                  std::strerror(errno) + " (does the folder exist and is it writable?)");
  }
  ::unlink(path.c_str());
  return f;
}

void MeshSpool::write(std::FILE* f, const void* data, size_t bytes) {
  if (bytes > 0 && std::fwrite(data, 1, bytes, f) != bytes) {
    throw IoError("cannot keep the surface the moving map leaves: writing to a temporary file in " +
                  folder_ + " failed: " + std::strerror(errno) + " (disk full?)");
  }
}

void MeshSpool::addVertices(const Eigen::Vector3f* positions, const Eigen::Vector3f* normals,
                            size_t count) {
  std::vector<float> rec(count * 6);
  for (size_t i = 0; i < count; ++i) {
    for (int c = 0; c < 3; ++c) {
      rec[i * 6 + c] = positions[i][c];
      rec[i * 6 + 3 + c] = normals[i][c];
    }
  }
  write(vertex_file_, rec.data(), rec.size() * sizeof(float));
  vertices_ += count;
}

void MeshSpool::addTriangles(const Eigen::Vector3i* triangles, size_t count) {
  std::vector<int32_t> rec(count * 3);
  for (size_t i = 0; i < count; ++i) {
    for (int c = 0; c < 3; ++c) rec[i * 3 + c] = triangles[i][c] + static_cast<int32_t>(part_base_);
  }
  write(triangle_file_, rec.data(), rec.size() * sizeof(int32_t));
  triangles_ += count;
}

void MeshSpool::replay(map::MeshSink& sink) const {
  const auto rewind = [this](std::FILE* f) {
    if (std::fflush(f) != 0 || std::fseek(f, 0, SEEK_SET) != 0) {
      throw IoError("cannot read back the surface the moving map left (temporary file in " +
                    folder_ + "): " + std::strerror(errno));
    }
  };
  rewind(vertex_file_);
  std::vector<float> v(kBatch * 6);
  std::vector<Eigen::Vector3f> p, n;
  for (size_t done = 0; done < vertices_;) {
    const size_t want = std::min(kBatch, vertices_ - done);
    if (std::fread(v.data(), sizeof(float) * 6, want, vertex_file_) != want) {
      throw IoError("cannot read back the surface the moving map left (temporary file in " +
                    folder_ + ")");
    }
    p.resize(want);
    n.resize(want);
    for (size_t i = 0; i < want; ++i) {
      p[i] = Eigen::Vector3f(v[i * 6], v[i * 6 + 1], v[i * 6 + 2]);
      n[i] = Eigen::Vector3f(v[i * 6 + 3], v[i * 6 + 4], v[i * 6 + 5]);
    }
    sink.addVertices(p.data(), n.data(), want);
    done += want;
  }
  rewind(triangle_file_);
  std::vector<int32_t> t(kBatch * 3);
  std::vector<Eigen::Vector3i> tri;
  for (size_t done = 0; done < triangles_;) {
    const size_t want = std::min(kBatch, triangles_ - done);
    if (std::fread(t.data(), sizeof(int32_t) * 3, want, triangle_file_) != want) {
      throw IoError("cannot read back the surface the moving map left (temporary file in " +
                    folder_ + ")");
    }
    tri.resize(want);
    for (size_t i = 0; i < want; ++i)
      tri[i] = Eigen::Vector3i(t[i * 3], t[i * 3 + 1], t[i * 3 + 2]);
    sink.addTriangles(tri.data(), want);
    done += want;
  }
  // Appending goes on at the end.
  if (std::fseek(vertex_file_, 0, SEEK_END) != 0 || std::fseek(triangle_file_, 0, SEEK_END) != 0) {
    throw IoError("cannot keep the surface the moving map leaves (temporary file in " + folder_ +
                  "): " + std::strerror(errno));
  }
}

}  // namespace emf::io
