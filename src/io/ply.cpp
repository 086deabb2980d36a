#include "io/ply.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <locale>
#include <sstream>
#include <vector>

#include "common/error.h"

namespace emf::io {

static_assert(sizeof(float) == 4 && sizeof(int32_t) == 4, "PLY float/int are 32-bit");

namespace {

/// Bytes reserved for the header at the start of the file: the longest header (20-digit counts)
/// is about 320 bytes; a comment line pads the real one to this size.
constexpr size_t kHeaderBytes = 400;

std::string plyHeader(bool binary, size_t vertices, size_t triangles) {
  std::ostringstream h;
  h.imbue(std::locale::classic());  // no digit grouping from the host program's global locale
  h << "ply\nformat " << (binary ? "binary_little_endian" : "ascii") << " 1.0\n"
    << "comment emf mesh: metres, normals point to the free side\n"
    << "element vertex " << vertices << "\n"
    << "property float x\nproperty float y\nproperty float z\n"
    << "property float nx\nproperty float ny\nproperty float nz\n"
    << "element face " << triangles << "\n"
    << "property list uchar int vertex_indices\n";
  std::string head = h.str();
  const std::string end = "end_header\n";
  const size_t pad = kHeaderBytes - head.size() - end.size();  // >= 60
  return head + "comment" + std::string(pad - 8, ' ') + "\n" + end;
}

}  // namespace

/// The triangles' temporary file: created next to the PLY and unlinked at once (it lives until
/// closed, and no crash can leave it behind).
class PlyWriter::FacePart {
 public:
  explicit FacePart(const std::string& target) {
    namespace fs = std::filesystem;
    static std::atomic<int> counter{0};
    const fs::path t(target);
    const fs::path dir = t.has_parent_path() ? t.parent_path() : fs::path(".");
    path_ = (dir / ("." + t.filename().string() + ".tmp-" +
                    std::to_string(static_cast<long>(::getpid())) + "-" +
                    std::to_string(counter++) + "-faces"))
                .string();
    file_ = std::fopen(path_.c_str(), "w+b");
    if (!file_) {
      throw IoError("cannot write mesh " + target + ": cannot create " + path_ + ": " +
                    std::strerror(errno) + " (does the folder exist and is it writable?)");
    }
    unlinked_ = ::unlink(path_.c_str()) == 0;
  }
  ~FacePart() {
    std::fclose(file_);
    if (!unlinked_) ::unlink(path_.c_str());
  }
  FacePart(const FacePart&) = delete;
  FacePart& operator=(const FacePart&) = delete;

  void write(const std::string& bytes, const std::string& target) {
    if (!bytes.empty() && std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size()) {
      throw IoError("cannot write mesh " + target + ": writing its triangles to " + path_ +
                    " failed: " + std::strerror(errno) + " (disk full?)");
    }
  }
  /// Appends the whole part to `out`.
  void copyTo(AtomicOutputFile& out, const std::string& target) {
    if (std::fflush(file_) != 0 || std::fseek(file_, 0, SEEK_SET) != 0) {
      throw IoError("cannot write mesh " + target + ": cannot read back its triangles from " +
                    path_ + ": " + std::strerror(errno));
    }
    std::vector<char> chunk(1 << 20);
    size_t n = 0;
    while ((n = std::fread(chunk.data(), 1, chunk.size(), file_)) > 0) out.write(chunk.data(), n);
    if (std::ferror(file_)) {
      throw IoError("cannot write mesh " + target + ": cannot read back its triangles from " +
                    path_);
    }
  }

 private:
  std::string path_;
  FILE* file_ = nullptr;
  bool unlinked_ = false;
};

PlyWriter::PlyWriter(std::string path, bool binary)
    : path_(std::move(path)),
      binary_(binary),
      out_(std::make_unique<AtomicOutputFile>(path_)),
      faces_(std::make_unique<FacePart>(path_)) {
  const std::string reserved(kHeaderBytes, ' ');
  out_->write(reserved.data(), reserved.size());
}

PlyWriter::~PlyWriter() = default;

void PlyWriter::addVertices(const Eigen::Vector3f* positions, const Eigen::Vector3f* normals,
                            size_t count) {
  buffer_.clear();
  if (binary_) {
    // Little-endian hosts only (x86-64, aarch64 in little-endian mode).
    buffer_.reserve(count * 24);
    for (size_t i = 0; i < count; ++i) {
      const float v[6] = {positions[i].x(), positions[i].y(), positions[i].z(),
                          normals[i].x(),   normals[i].y(),   normals[i].z()};
      buffer_.append(reinterpret_cast<const char*>(v), sizeof(v));
    }
  } else {
    std::ostringstream os;
    os.imbue(std::locale::classic());
    os.precision(9);
    for (size_t i = 0; i < count; ++i) {
      os << positions[i].x() << ' ' << positions[i].y() << ' ' << positions[i].z() << ' '
         << normals[i].x() << ' ' << normals[i].y() << ' ' << normals[i].z() << '\n';
    }
    buffer_ = os.str();
  }
  out_->write(buffer_.data(), buffer_.size());
  vertices_ += count;
}

void PlyWriter::addTriangles(const Eigen::Vector3i* triangles, size_t count) {
  buffer_.clear();
  if (binary_) {
    buffer_.reserve(count * 13);
    for (size_t i = 0; i < count; ++i) {
      const uint8_t n = 3;
      const int32_t idx[3] = {triangles[i].x(), triangles[i].y(), triangles[i].z()};
      buffer_.append(reinterpret_cast<const char*>(&n), 1);
      buffer_.append(reinterpret_cast<const char*>(idx), sizeof(idx));
    }
  } else {
    std::ostringstream os;
    os.imbue(std::locale::classic());
    for (size_t i = 0; i < count; ++i) {
      os << "3 " << triangles[i].x() << ' ' << triangles[i].y() << ' ' << triangles[i].z() << '\n';
    }
    buffer_ = os.str();
  }
  faces_->write(buffer_, path_);
  triangles_ += count;
}

void PlyWriter::commit() {
  if (!out_) return;  // committed already
  try {
    faces_->copyTo(*out_, path_);
    const std::string header = plyHeader(binary_, vertices_, triangles_);
    out_->writeAt(0, header.data(), header.size());
    out_->commit();
  } catch (const IoError& e) {
    const std::string what = e.what();
    if (what.find(path_) != std::string::npos) throw;
    throw IoError("cannot write mesh " + path_ + ": " + what);
  }
  out_.reset();
  faces_.reset();
}

void writePly(const std::string& path, const map::Mesh& mesh, bool binary) {
  PlyWriter w(path, binary);
  w.addVertices(mesh.vertices.data(), mesh.normals.data(), mesh.vertices.size());
  w.addTriangles(mesh.triangles.data(), mesh.triangles.size());
  w.commit();
}

map::Mesh readPly(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot open PLY file " + path);
  in.imbue(std::locale::classic());
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
    ls.imbue(std::locale::classic());
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
  map::Mesh m;
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

}  // namespace emf::io
