#include <cstdio>

#include "cli/arg_parser.h"
#include "cli/commands.h"
#include "cli/load_config.h"

namespace emf::cli {

int cmdConfig(const std::vector<std::string>& args) {
  std::string config_file;
  std::vector<std::string> sets;
  bool list = false;
  ArgParser p("config",
              "Checks a configuration (--config, --set) and prints the resulting values as "
              "YAML, or lists every key with its type, range, unit and default (--list).");
  p.option("config", &config_file, "FILE", "YAML configuration to check (conf/*.yaml)");
  p.repeated("set", &sets, "SECTION.KEY=VALUE", "override one key");
  p.flag("list", &list, "list every key with type, range, unit and default");
  if (auto code = p.parse(args)) return *code;
  if (list) {
    for (const auto& o : listOptions()) {
      std::printf("%s.%s  (%s%s%s%s%s) default %s\n    %s\n", o.section.c_str(), o.key.c_str(),
                  o.type.c_str(), o.range.empty() ? "" : " ", o.range.c_str(),
                  o.unit.empty() ? "" : ", ", o.unit.c_str(), o.default_value.c_str(),
                  o.doc.c_str());
    }
    return kExitOk;
  }
  const Config c = loadConfig(config_file, sets);
  std::printf("%s", c.toYaml().c_str());
  return kExitOk;
}

}  // namespace emf::cli
