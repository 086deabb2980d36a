// Checked command-line arguments for the bench/ programs. A bad number, a value out of range, a
// missing value or an unknown option is a UsageError naming the option; each program's main
// prints "<program>: <message>" and its usage and exits with 2. Never a silent 0 from atoi, an
// uncaught std::stoi exception or a run with garbage settings.
#pragma once

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace emf::bench {

/// Exit code of a usage error (as the `emf` tool's).
constexpr int kExitUsage = 2;

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// `text` (all of it, base 10) as an integer in [lo, hi]; a UsageError naming `option` otherwise.
inline long parseInteger(const std::string& option, const std::string& text, long lo, long hi) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno == ERANGE || v < lo || v > hi) {
    throw UsageError(option + " '" + text + "': expected an integer in [" + std::to_string(lo) +
                     ", " + std::to_string(hi) + "]");
  }
  return v;
}

/// `text` (all of it) as a finite number in [lo, hi]; a UsageError naming `option` otherwise.
inline double parseReal(const std::string& option, const std::string& text, double lo, double hi) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v) || v < lo || v > hi) {
    throw UsageError(option + " '" + text + "': expected a number in [" + std::to_string(lo) +
                     ", " + std::to_string(hi) + "]");
  }
  return v;
}

/// Walks argv once: `while (args.next()) { if (args.is("--frames")) n = args.integer(1, 100); ...
/// else args.unknown(); }`.
class ArgWalker {
 public:
  ArgWalker(int argc, char** argv) : argc_(argc), argv_(argv) {}

  /// Moves to the next argument; false after the last one.
  bool next() {
    if (++i_ >= argc_) return false;
    current_ = argv_[i_];
    return true;
  }
  const std::string& current() const { return current_; }
  bool is(const char* option) const { return current_ == option; }

  /// The argument after the current option, consumed; a UsageError when there is none.
  std::string value() {
    if (i_ + 1 >= argc_) throw UsageError(current_ + " needs a value");
    return argv_[++i_];
  }
  long integer(long lo, long hi) {
    const std::string option = current_;
    return parseInteger(option, value(), lo, hi);
  }
  double real(double lo, double hi) {
    const std::string option = current_;
    return parseReal(option, value(), lo, hi);
  }
  [[noreturn]] void unknown() const { throw UsageError("unknown option '" + current_ + "'"); }

 private:
  int argc_;
  char** argv_;
  int i_ = 0;
  std::string current_;
};

}  // namespace emf::bench
