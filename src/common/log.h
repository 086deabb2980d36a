// Minimal leveled logging to stderr. The threshold is process-wide (set once at start-up from
// the CLI / C API / EMF_LOG_LEVEL); messages are written with one fprintf call so lines from
// different threads do not interleave.
#pragma once

#include <sstream>
#include <string>

namespace emf {

enum class LogLevel { kDebug = 0, kInfo = 1, kWarning = 2, kError = 3, kOff = 4 };

/// Sets the threshold; messages below it are dropped.
void setLogLevel(LogLevel level);
LogLevel logLevel();
/// Parses "debug|info|warning|error|off"; returns false if unknown.
bool parseLogLevel(const std::string& text, LogLevel* level);
/// Writes one line "emf: <level>: <message>" to stderr if level >= threshold.
void logMessage(LogLevel level, const std::string& message);

namespace detail {
template <typename... Args>
std::string concat(const Args&... args) {
  std::ostringstream os;
  (os << ... << args);
  return os.str();
}
}  // namespace detail

template <typename... Args>
void logDebug(const Args&... args) {
  if (logLevel() <= LogLevel::kDebug) logMessage(LogLevel::kDebug, detail::concat(args...));
}
template <typename... Args>
void logInfo(const Args&... args) {
  if (logLevel() <= LogLevel::kInfo) logMessage(LogLevel::kInfo, detail::concat(args...));
}
template <typename... Args>
void logWarning(const Args&... args) {
  if (logLevel() <= LogLevel::kWarning) logMessage(LogLevel::kWarning, detail::concat(args...));
}
template <typename... Args>
void logError(const Args&... args) {
  if (logLevel() <= LogLevel::kError) logMessage(LogLevel::kError, detail::concat(args...));
}

}  // namespace emf
