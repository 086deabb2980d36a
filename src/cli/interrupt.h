// Ctrl-C / SIGTERM / SIGHUP during a long command: the signal asks the command to stop after the
// current frame and still write its outputs. Further signals change nothing (the folder ends the
// same whatever their number); each prints that the outputs are being written. SIGKILL ends at
// once and still leaves the trajectories written so far (emf run streams them).
#pragma once

namespace emf::cli {

/// First thing in main(): from here on the three signals are recorded, not fatal, so one that
/// arrives while the process starts (before a command installs its InterruptGuard) is kept.
void catchInterruptsEarly();
/// For commands that do not stop gracefully: the previous actions are restored and a signal
/// recorded since catchInterruptsEarly() is raised again (the default action ends the process).
void releaseEarlyInterrupts();

/// The handlers for a command's lifetime (restores the previous actions after). A signal that
/// arrived since catchInterruptsEarly() counts as requested. One at a time per process.
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
  /// "SIGINT" / "SIGTERM" / "SIGHUP".
  const char* signalName() const;
  /// 128 + the signal's number, the shell's convention for a run ended by a signal.
  int exitCode() const;
};

}  // namespace emf::cli
