#include "pipeline/plugin_search_path.h"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <sstream>

namespace emf::pipeline {
namespace {
namespace fs = std::filesystem;

/// The file this code runs from: libemf.so, or the executable it is linked into.
fs::path thisModule() {
  static const int kAnchor = 0;
  Dl_info info{};
  std::error_code ec;
  if (dladdr(&kAnchor, &info) != 0 && info.dli_fname) {
    const fs::path p = info.dli_fname;
    // The main program may be named as it was started (relative, or by PATH lookup).
    if (p.filename().string().find(".so") != std::string::npos) {
      return fs::weakly_canonical(p, ec);
    }
  }
  return fs::read_symlink("/proc/self/exe", ec);
}

/// Whether `path` lies inside `folder` (both absolute).
bool isInside(const fs::path& path, const fs::path& folder) {
  const std::string p = path.lexically_normal().string();
  const std::string f = folder.lexically_normal().string();
  return !f.empty() && p.compare(0, f.size(), f) == 0 &&
         (p.size() == f.size() || p[f.size()] == '/');
}

}  // namespace

std::vector<std::string> modulePluginFolders() {
  std::vector<std::string> out;
  const fs::path self = thisModule();
  if (self.empty()) return out;
#if defined(EMF_INSTALL_LIBDIR) && defined(EMF_INSTALL_BINDIR)
  // Installed: <prefix>/<bindir>/emf or <prefix>/<libdir>/libemf.so -> <prefix>/<libdir>/emf/
  // plugins, wherever the prefix was installed or moved to (even inside a build tree).
  const fs::path dir = self.parent_path();
  const fs::path bindir = EMF_INSTALL_BINDIR, libdir = EMF_INSTALL_LIBDIR;
  auto prefixOf = [&dir](const fs::path& rel) {
    fs::path p = dir;
    for (auto it = rel.begin(); it != rel.end(); ++it) p = p.parent_path();
    return p;
  };
  const fs::path prefix = dir.filename() == bindir.filename() ? prefixOf(bindir) : prefixOf(libdir);
  const fs::path installed = prefix / libdir / "emf" / "plugins";
  std::error_code ec;
  if (fs::is_directory(installed, ec)) {
    out.push_back(installed.string());
    return out;
  }
#endif
#ifdef EMF_BUILD_PLUGIN_DIR
  // The build tree's plugins only for the build tree's own binaries: an installed copy must not
  // pick up whatever a later build left there.
  if (isInside(self, fs::path(EMF_BUILD_PLUGIN_DIR).parent_path())) {
    out.push_back(EMF_BUILD_PLUGIN_DIR);
    return out;
  }
#endif
#if defined(EMF_INSTALL_LIBDIR) && defined(EMF_INSTALL_BINDIR)
  out.push_back(installed.string());  // named in the "not found" list even when missing
#endif
  return out;
}

std::vector<std::string> pluginSearchPath(const DetectorOptions& options) {
  std::vector<std::string> out = options.search_path;
  if (const char* env = std::getenv("EMF_PLUGIN_PATH"); env && *env) {
    std::stringstream ss(env);
    std::string item;
    while (std::getline(ss, item, ':')) {
      if (!item.empty()) out.push_back(item);
    }
  }
  for (const std::string& folder : modulePluginFolders()) out.push_back(folder);
  return out;
}

}  // namespace emf::pipeline
