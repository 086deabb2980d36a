#include "common/log.h"

#include <atomic>
#include <cstdio>
#include <cstdlib>

namespace emf {
namespace {

LogLevel initialLevel() {
  LogLevel level = LogLevel::kInfo;
  if (const char* env = std::getenv("EMF_LOG_LEVEL")) parseLogLevel(env, &level);
  return level;
}

std::atomic<int>& threshold() {
  static std::atomic<int> value{static_cast<int>(initialLevel())};
  return value;
}

const char* levelName(LogLevel level) {
  switch (level) {
    case LogLevel::kDebug:
      return "debug";
    case LogLevel::kInfo:
      return "info";
    case LogLevel::kWarning:
      return "warning";
    case LogLevel::kError:
      return "error";
    case LogLevel::kOff:
      return "off";
  }
  return "?";
}

}  // namespace

void setLogLevel(LogLevel level) { threshold().store(static_cast<int>(level)); }

LogLevel logLevel() { return static_cast<LogLevel>(threshold().load(std::memory_order_relaxed)); }

bool parseLogLevel(const std::string& text, LogLevel* level) {
  static const struct {
    const char* name;
    LogLevel level;
  } kNames[] = {{"debug", LogLevel::kDebug},
                {"info", LogLevel::kInfo},
                {"warning", LogLevel::kWarning},
                {"error", LogLevel::kError},
                {"off", LogLevel::kOff}};
  for (const auto& n : kNames) {
    if (text == n.name) {
      *level = n.level;
      return true;
    }
  }
  return false;
}

void logMessage(LogLevel level, const std::string& message) {
  if (static_cast<int>(level) < threshold().load(std::memory_order_relaxed)) return;
  std::fprintf(stderr, "emf: %s: %s\n", levelName(level), message.c_str());
}

}  // namespace emf
