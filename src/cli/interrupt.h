// Ctrl-C / SIGTERM during a long command: the first signal asks the command to stop at the next
// frame and still write its outputs; a second one terminates at once (default action).
#pragma once

namespace emf::cli {

/// Installs SIGINT and SIGTERM handlers for its lifetime (restores the previous ones after).
/// One at a time per process.
class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;

  /// A signal arrived: finish the current frame, write the outputs, exit with exitCode().
  bool requested() const;
  /// The signal's number (0 = none).
  int signalNumber() const;
  /// "SIGINT" / "SIGTERM".
  const char* signalName() const;
  /// 128 + the signal's number, the shell's convention for a run ended by a signal.
  int exitCode() const;
};

}  // namespace emf::cli
