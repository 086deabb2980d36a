// Where detector plugins are looked up by name.
#pragma once

#include <string>
#include <vector>

#include "pipeline/pipeline_options.h"

namespace emf::pipeline {

/// Folders searched for a plugin given by name, in order: detector.search_path (config),
/// $EMF_PLUGIN_PATH (colon-separated), then modulePluginFolders().
std::vector<std::string> pluginSearchPath(const DetectorOptions& options);

/// The plugins that belong to the running emf: the build tree's plugins folder when this code
/// runs from the build tree, else <prefix>/<libdir>/emf/plugins of the installation it runs
/// from (found from libemf.so's or the executable's own location, so a moved prefix works).
std::vector<std::string> modulePluginFolders();

}  // namespace emf::pipeline
