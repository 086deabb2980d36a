#include "pipeline/plugin_search_path.h"

#include <cstdlib>
#include <sstream>

namespace emf::pipeline {

std::vector<std::string> pluginSearchPath(const DetectorOptions& options) {
  std::vector<std::string> out = options.search_path;
  if (const char* env = std::getenv("EMF_PLUGIN_PATH"); env && *env) {
    std::stringstream ss(env);
    std::string item;
    while (std::getline(ss, item, ':')) {
      if (!item.empty()) out.push_back(item);
    }
  }
#ifdef EMF_BUILD_PLUGIN_DIR
  out.push_back(EMF_BUILD_PLUGIN_DIR);
#endif
#ifdef EMF_INSTALL_PLUGIN_DIR
  out.push_back(EMF_INSTALL_PLUGIN_DIR);
#endif
  return out;
}

}  // namespace emf::pipeline
