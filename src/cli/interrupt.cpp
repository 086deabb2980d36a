#include "cli/interrupt.h"

#include <atomic>
#include <csignal>
#include <cstring>

#include "common/error.h"

namespace emf::cli {
namespace {

volatile std::sig_atomic_t g_signal = 0;
std::atomic<bool> g_installed{false};
struct sigaction g_previous_int, g_previous_term;

extern "C" void onSignal(int signal) {
  if (g_signal != 0) {
    // Second signal: the user insists; terminate with the default action.
    std::signal(signal, SIG_DFL);
    std::raise(signal);
    return;
  }
  g_signal = signal;
}

}  // namespace

InterruptGuard::InterruptGuard() {
  if (g_installed.exchange(true)) {
    throw StateError("InterruptGuard: only one may exist at a time");
  }
  g_signal = 0;
  struct sigaction action;
  std::memset(&action, 0, sizeof(action));
  action.sa_handler = onSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;  // blocking reads resume; the loop checks requested()
  // A signal the parent set to be ignored (e.g. SIGINT of a background job) stays ignored.
  sigaction(SIGINT, nullptr, &g_previous_int);
  sigaction(SIGTERM, nullptr, &g_previous_term);
  if (g_previous_int.sa_handler != SIG_IGN) sigaction(SIGINT, &action, nullptr);
  if (g_previous_term.sa_handler != SIG_IGN) sigaction(SIGTERM, &action, nullptr);
}

InterruptGuard::~InterruptGuard() {
  sigaction(SIGINT, &g_previous_int, nullptr);
  sigaction(SIGTERM, &g_previous_term, nullptr);
  g_installed.store(false);
}

bool InterruptGuard::requested() const { return g_signal != 0; }

int InterruptGuard::signalNumber() const { return static_cast<int>(g_signal); }

const char* InterruptGuard::signalName() const {
  switch (g_signal) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    default:
      return "no signal";
  }
}

int InterruptGuard::exitCode() const { return 128 + static_cast<int>(g_signal); }

}  // namespace emf::cli
