// `emf`: the command-line tool. Dispatches to subcommands; every error is a message on stderr
// and a non-zero exit code (1 = failure, 2 = usage).
#include <csignal>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "cli/arg_parser.h"
#include "cli/commands.h"
#include "cli/interrupt.h"
#include "pipeline/config.h"

namespace {

using emf::cli::Command;

const std::vector<Command>& commands() {
  static const std::vector<Command> kCommands = {
      {"run", "run the SLAM on a source; writes trajectory, meshes and a summary",
       emf::cli::cmdRun},
      {"info", "version, OpenCL devices (and the selected one), backends, plugin path",
       emf::cli::cmdInfo},
      {"version", "print the version", emf::cli::cmdVersion},
      {"config", "list, check or print configuration keys", emf::cli::cmdConfig},
      {"eval", "trajectory errors (ATE, RPE) of the camera and objects vs ground truth",
       emf::cli::cmdEval},

      {"synth", "render a synthetic dynamic scene into a TUM folder with ground truth",
       emf::cli::cmdSynth},

      {"devices", "list connected RGB-D sensors and their backends; watch hot-plug",
       emf::cli::cmdDevices},
  };
  return kCommands;
}

void printUsage(FILE* out) {
  std::fprintf(out, "usage: emf <command> [options]   (emf <command> --help for details)\n\n");
  std::fprintf(out, "commands:\n");
  for (const auto& c : commands()) std::fprintf(out, "  %-10s %s\n", c.name, c.summary);
}

}  // namespace

int main(int argc, char** argv) {
  // Before anything else: a Ctrl-C while `emf run` starts must not kill it without its outputs.
  emf::cli::catchInterruptsEarly();
  // A file size limit (ulimit -f) makes the write fail with EFBIG, which names the file, instead
  // of killing the process without its outputs.
  std::signal(SIGXFSZ, SIG_IGN);
  if (argc < 2 || std::string(argv[1]) != "run") emf::cli::releaseEarlyInterrupts();
  if (argc < 2) {
    printUsage(stderr);
    return emf::cli::kExitUsage;
  }
  const std::string name = argv[1];
  if (name == "--help" || name == "-h" || name == "help") {
    printUsage(stdout);
    return emf::cli::kExitOk;
  }
  if (name == "--version") return emf::cli::cmdVersion({});
  const std::vector<std::string> args(argv + 2, argv + argc);
  for (const auto& c : commands()) {
    if (name != c.name) continue;
    try {
      return c.run(args);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "emf %s: error: %s\n", c.name, e.what());
      return emf::cli::kExitFailure;
    }
  }
  std::string best;
  int best_d = 4;
  for (const auto& c : commands()) {
    const int d = emf::editDistance(name, c.name);
    if (d < best_d) {
      best_d = d;
      best = c.name;
    }
  }
  std::fprintf(stderr, "emf: unknown command '%s'%s\n\n", name.c_str(),
               best.empty() ? "" : (" (did you mean '" + best + "'?)").c_str());
  printUsage(stderr);
  return emf::cli::kExitUsage;
}
