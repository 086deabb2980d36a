// The `emf` subcommands. Each lives in its own cmd_<name>.cpp and is listed in main.cpp.
#pragma once

#include <string>
#include <vector>

namespace emf::cli {

/// Runs a subcommand with its arguments (argv after the subcommand). Returns the exit code.
using CommandFn = int (*)(const std::vector<std::string>& args);

struct Command {
  const char* name;
  const char* summary;
  CommandFn run;
};

int cmdInfo(const std::vector<std::string>& args);
int cmdVersion(const std::vector<std::string>& args);
int cmdConfig(const std::vector<std::string>& args);
int cmdEval(const std::vector<std::string>& args);

int cmdSynth(const std::vector<std::string>& args);
int cmdRun(const std::vector<std::string>& args);

int cmdDevices(const std::vector<std::string>& args);

}  // namespace emf::cli
