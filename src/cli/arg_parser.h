// A small command-line parser for the `emf` subcommands: --long options with a value
// (`--out DIR` or `--out=DIR`), boolean flags, repeated options and positionals. Every
// subcommand has --help. Unknown flags and missing values are usage errors (exit code 2).
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace emf::cli {

constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;
constexpr int kExitUsage = 2;

class ArgParser {
 public:
  ArgParser(std::string command, std::string summary);

  void flag(const std::string& name, bool* value, const std::string& help);
  void option(const std::string& name, std::string* value, const std::string& meta,
              const std::string& help);
  void repeated(const std::string& name, std::vector<std::string>* values, const std::string& meta,
                const std::string& help);
  void positional(const std::string& name, std::string* value, const std::string& help,
                  bool required = true);

  /// Parses argv (without the program and subcommand names). Returns nullopt to continue, or
  /// the exit code to return: 0 after --help, 2 after a usage error (message + usage printed).
  std::optional<int> parse(const std::vector<std::string>& args);
  std::string usage() const;

 private:
  struct Opt {
    std::string name, meta, help;
    bool* flag = nullptr;
    std::string* value = nullptr;
    std::vector<std::string>* values = nullptr;
  };
  struct Pos {
    std::string name, help;
    std::string* value;
    bool required;
  };
  const Opt* find(const std::string& name) const;

  std::string command_, summary_;
  std::vector<Opt> opts_;
  std::vector<Pos> pos_;
};

}  // namespace emf::cli
