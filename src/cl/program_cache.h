// On-disk cache of compiled OpenCL program binaries.
//
// Key: kernel source SHA-256, build options, device name, device driver version and platform
// version. One file per key (name = 64-bit FNV-1a of the key), holding the full key so a hash
// collision or a foreign file is detected. Files are written atomically (temp + rename). An
// unusable cache (folder not creatable, unwritable, corrupt file) never fails a build: the
// program is compiled from source and a warning says why.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace emf::cl {

class ProgramCache {
 public:
  /// `dir` = "" picks $XDG_CACHE_HOME/emf/kernels or $HOME/.cache/emf/kernels.
  explicit ProgramCache(std::string dir, bool enabled = true);

  /// The binary stored for `key`, or empty if absent/unreadable/mismatched.
  std::vector<unsigned char> load(const std::string& key) const;
  /// Stores atomically; returns false (and warns) if the cache is unusable.
  bool store(const std::string& key, const std::vector<unsigned char>& binary) const;

  const std::string& dir() const { return dir_; }
  bool enabled() const { return enabled_; }
  /// The file that holds `key`.
  std::string pathFor(const std::string& key) const;

  static std::string defaultDir();
  static uint64_t fnv1a64(const std::string& text);

 private:
  std::string dir_;
  bool enabled_;
};

}  // namespace emf::cl
