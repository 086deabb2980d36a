#include "cli/load_config.h"

namespace emf::cli {

Config loadConfig(const std::string& config_file, const std::vector<std::string>& sets) {
  Config c = config_file.empty() ? Config() : Config::loadFile(config_file);
  for (const auto& s : sets) c.set(s);
  c.validate();
  return c;
}

}  // namespace emf::cli
