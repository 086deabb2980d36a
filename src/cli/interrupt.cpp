#include "cli/interrupt.h"

#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstring>

#include "common/error.h"

namespace emf::cli {
namespace {

constexpr int kSignals[] = {SIGINT, SIGTERM, SIGHUP};
constexpr int kNumSignals = 3;

volatile std::sig_atomic_t g_signal = 0;
std::atomic<bool> g_early{false};
std::atomic<bool> g_guarded{false};
struct sigaction g_previous[kNumSignals];

extern "C" void onSignal(int signal) {
  if (g_signal != 0) {
    // Only async-signal-safe calls here: write(2), no allocation, no stdio.
    static const char kMessage[] =
        "\nemf: already stopping after the current frame and writing the outputs\n";
    const ssize_t ignored = write(STDERR_FILENO, kMessage, sizeof(kMessage) - 1);
    (void)ignored;
    return;
  }
  g_signal = signal;
}

void install() {
  struct sigaction action;
  std::memset(&action, 0, sizeof(action));
  action.sa_handler = onSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;  // blocking reads resume; the loop checks requested()
  for (int i = 0; i < kNumSignals; ++i) {
    sigaction(kSignals[i], nullptr, &g_previous[i]);
    // A signal the parent set to be ignored (e.g. SIGINT of a background job) stays ignored.
    if (g_previous[i].sa_handler != SIG_IGN) sigaction(kSignals[i], &action, nullptr);
  }
}

void restore() {
  for (int i = 0; i < kNumSignals; ++i) sigaction(kSignals[i], &g_previous[i], nullptr);
}

}  // namespace

void catchInterruptsEarly() {
  if (g_early.exchange(true)) return;
  g_signal = 0;
  install();
}

void releaseEarlyInterrupts() {
  if (!g_early.exchange(false)) return;
  restore();
  if (g_signal != 0) std::raise(static_cast<int>(g_signal));
}

InterruptGuard::InterruptGuard() {
  if (g_guarded.exchange(true)) {
    throw StateError("InterruptGuard: only one may exist at a time");
  }
  // Installed early by main(): keep the handlers and any signal already recorded.
  if (!g_early.load()) {
    g_signal = 0;
    install();
  }
}

InterruptGuard::~InterruptGuard() {
  g_early.store(false);
  restore();
  g_guarded.store(false);
}

bool InterruptGuard::requested() const { return g_signal != 0; }

int InterruptGuard::signalNumber() const { return static_cast<int>(g_signal); }

const char* InterruptGuard::signalName() const {
  switch (g_signal) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    case SIGHUP:
      return "SIGHUP";
    default:
      return "no signal";
  }
}

int InterruptGuard::exitCode() const { return 128 + static_cast<int>(g_signal); }

}  // namespace emf::cli
