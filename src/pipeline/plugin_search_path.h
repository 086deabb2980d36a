// Where detector plugins are looked up by name.
#pragma once

#include <string>
#include <vector>

#include "pipeline/pipeline_options.h"

namespace emf::pipeline {

/// Folders searched for a plugin given by name, in order: detector.search_path (config),
/// $EMF_PLUGIN_PATH (colon-separated), the build tree's plugins folder (when running from a
/// build), and <prefix>/lib/emf/plugins of the installation.
std::vector<std::string> pluginSearchPath(const DetectorOptions& options);

}  // namespace emf::pipeline
