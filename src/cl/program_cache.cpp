#include "cl/program_cache.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "common/log.h"

namespace emf::cl {
namespace fs = std::filesystem;

namespace {
constexpr char kMagic[] = "EMFCLBIN1\n";
}

uint64_t ProgramCache::fnv1a64(const std::string& text) {
  uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

std::string ProgramCache::defaultDir() {
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) {
    return std::string(xdg) + "/emf/kernels";
  }
  if (const char* home = std::getenv("HOME"); home && *home) {
    return std::string(home) + "/.cache/emf/kernels";
  }
  return (fs::temp_directory_path() / "emf-kernels").string();
}

ProgramCache::ProgramCache(std::string dir, bool enabled)
    : dir_(dir.empty() ? defaultDir() : std::move(dir)), enabled_(enabled) {}

std::string ProgramCache::pathFor(const std::string& key) const {
  char name[32];
  std::snprintf(name, sizeof(name), "%016llx.bin", static_cast<unsigned long long>(fnv1a64(key)));
  return (fs::path(dir_) / name).string();
}

std::vector<unsigned char> ProgramCache::load(const std::string& key) const {
  if (!enabled_) return {};
  const std::string path = pathFor(key);
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t magic_len = sizeof(kMagic) - 1;
  const size_t header = magic_len + 2 * sizeof(uint64_t);
  if (data.size() < header || data.compare(0, magic_len, kMagic) != 0) {
    logWarning("kernel cache file ", path, " is corrupt; compiling from source");
    return {};
  }
  uint64_t key_len = 0, bin_len = 0;
  std::memcpy(&key_len, data.data() + magic_len, sizeof(key_len));
  std::memcpy(&bin_len, data.data() + magic_len + sizeof(key_len), sizeof(bin_len));
  if (data.size() != header + key_len + bin_len) {
    logWarning("kernel cache file ", path, " is truncated; compiling from source");
    return {};
  }
  if (data.compare(header, key_len, key) != 0) {
    return {};  // a different program with the same hash: treat as a miss
  }
  const auto* begin = reinterpret_cast<const unsigned char*>(data.data() + header + key_len);
  return std::vector<unsigned char>(begin, begin + bin_len);
}

bool ProgramCache::store(const std::string& key, const std::vector<unsigned char>& binary) const {
  if (!enabled_) return false;
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) {
    logWarning("kernel cache folder ", dir_, " cannot be created (", ec.message(),
               "); kernels will be compiled on every start (set cl.cache_dir)");
    return false;
  }
  const std::string path = pathFor(key);
  std::random_device rd;
  const std::string tmp = path + ".tmp" + std::to_string(rd());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) {
      logWarning("kernel cache folder ", dir_,
                 " is not writable; kernels will be compiled on every start (set cl.cache_dir)");
      return false;
    }
    const uint64_t key_len = key.size(), bin_len = binary.size();
    out.write(kMagic, sizeof(kMagic) - 1);
    out.write(reinterpret_cast<const char*>(&key_len), sizeof(key_len));
    out.write(reinterpret_cast<const char*>(&bin_len), sizeof(bin_len));
    out.write(key.data(), static_cast<std::streamsize>(key.size()));
    out.write(reinterpret_cast<const char*>(binary.data()),
              static_cast<std::streamsize>(binary.size()));
    if (!out.flush()) {
      logWarning("writing kernel cache file ", tmp, " failed (disk full?)");
      out.close();
      fs::remove(tmp, ec);
      return false;
    }
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    logWarning("kernel cache: cannot rename ", tmp, " to ", path, ": ", ec.message());
    fs::remove(tmp, ec);
    return false;
  }
  return true;
}

}  // namespace emf::cl
