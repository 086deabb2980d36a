#include <cstdio>

#include "cli/arg_parser.h"
#include "cli/commands.h"
#include "emf/emf.h"

namespace emf::cli {

int cmdVersion(const std::vector<std::string>& args) {
  ArgParser p("version", "Prints the emf version (major.minor.patch).");
  if (auto code = p.parse(args)) return *code;
  std::printf("emf %d.%d.%d\n", EMF_VERSION_MAJOR, EMF_VERSION_MINOR, EMF_VERSION_PATCH);
  return kExitOk;
}

}  // namespace emf::cli
