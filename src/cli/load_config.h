// Shared by the subcommands: --config FILE plus --set section.key=value overrides.
#pragma once

#include <string>
#include <vector>

#include "pipeline/config.h"

namespace emf::cli {

/// Defaults, then `config_file` (if not empty), then each `sets` entry. Throws ConfigError.
Config loadConfig(const std::string& config_file, const std::vector<std::string>& sets);

}  // namespace emf::cli
