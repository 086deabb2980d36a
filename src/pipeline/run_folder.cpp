#include "pipeline/run_folder.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "common/error.h"
#include "common/log.h"

namespace emf::pipeline {
namespace fs = std::filesystem;

namespace {

// Held with flock() while a run writes into the folder; holds the writer's pid for messages.
constexpr const char* kLockName = ".emf-run.lock";

std::string utcStamp(const char* format) {
  const std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&t, &tm);
  char text[32];
  std::strftime(text, sizeof(text), format, &tm);
  return text;
}

// "run <id> (status, N frames)" from an earlier run.json, for the message; "" if unreadable.
std::string describeEarlierRun(const std::string& run_json) {
  std::ifstream in(run_json);
  if (!in) return "";
  std::stringstream text;
  text << in.rdbuf();
  const nlohmann::json j = nlohmann::json::parse(text.str(), nullptr, /*allow_exceptions=*/false);
  if (!j.is_object()) return "";
  std::string out = "run " + j.value("run_id", std::string("(no id)"));
  out += " (" + j.value("status", std::string("status unknown"));
  if (j.contains("frames") && j["frames"].is_number()) {
    out += ", " + std::to_string(j["frames"].get<int64_t>()) + " frames";
  }
  return out + ")";
}

}  // namespace

std::string utcNow() { return utcStamp("%Y-%m-%dT%H:%M:%SZ"); }

bool RunFolder::isRunOutput(const std::string& name) {
  static const std::regex kObjectFile("object-[0-9]+\\.(txt|ply)");
  return name == "run.json" || name == "camera.txt" || name == "background.ply" ||
         name == "images" || name == "eval.json" || name == "eval.png" ||
         std::regex_match(name, kObjectFile);
}

bool RunFolder::isTemporary(const std::string& name) {
  static const std::regex kTemporary(".+\\.tmp-[0-9]+-[0-9]+");
  return std::regex_match(name, kTemporary);
}

RunFolder::RunFolder(std::string dir, bool replace) : dir_(std::move(dir)) {
  const std::string what = "output folder '" + dir_ + "' (--out)";
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec || !fs::is_directory(dir_)) {
    throw IoError("cannot create the " + what + ": " +
                  (ec ? ec.message() : std::string("a file of that name exists")) +
                  "; choose another --out");
  }
  // The lock file is the first thing written: it proves the folder writable before any frame.
  lock_path_ = path(kLockName);
  lock_fd_ = ::open(lock_path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock_fd_ < 0) {
    throw IoError("cannot write into the " + what + ": " + std::strerror(errno) +
                  "; make it writable or choose another --out");
  }
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    char pid[32] = {0};
    const ssize_t n = ::pread(lock_fd_, pid, sizeof(pid) - 1, 0);
    ::close(lock_fd_);
    lock_fd_ = -1;
    throw IoError("another emf run" +
                  (n > 0 ? std::string(" (pid ") + std::string(pid, static_cast<size_t>(n)) + ")"
                         : std::string()) +
                  " is writing into the " + what + "; wait for it or choose another --out");
  }
  const std::string pid = std::to_string(::getpid());
  if (::ftruncate(lock_fd_, 0) != 0 ||
      ::pwrite(lock_fd_, pid.data(), pid.size(), 0) != static_cast<ssize_t>(pid.size())) {
    const std::string err = std::strerror(errno);
    ::close(lock_fd_);
    lock_fd_ = -1;
    throw IoError("cannot write into the " + what + ": " + err +
                  " (disk full?); free space or choose another --out");
  }

  std::vector<fs::path> earlier, temporaries;
  for (const auto& e : fs::directory_iterator(dir_, ec)) {
    const std::string name = e.path().filename().string();
    if (isRunOutput(name)) earlier.push_back(e.path());
    if (isTemporary(name)) temporaries.push_back(e.path());
  }
  if (!earlier.empty() && !replace) {
    std::string names;
    for (size_t i = 0; i < earlier.size() && i < 4; ++i) {
      names += (i ? ", " : "") + earlier[i].filename().string();
    }
    if (earlier.size() > 4) names += ", ...";
    const std::string run = describeEarlierRun(path("run.json"));
    ::close(lock_fd_);
    lock_fd_ = -1;
    throw IoError("the " + what + " holds the outputs of an earlier " +
                  (run.empty() ? std::string("run") : run) + ": " + names +
                  "; pass --force to replace them, or choose another --out");
  }
  for (const fs::path& p : replace ? earlier : std::vector<fs::path>{}) {
    fs::remove_all(p, ec);
    if (ec) {
      ::close(lock_fd_);
      lock_fd_ = -1;
      throw IoError("--force: cannot remove '" + p.string() +
                    "' of an earlier run: " + ec.message());
    }
    removed_.push_back(p.filename().string());
  }
  for (const fs::path& p : temporaries) {
    fs::remove(p, ec);
    if (!ec) removed_.push_back(p.filename().string());
    logWarning("'", p.string(), "' is a temporary file of an interrupted write",
               ec ? ": cannot remove it: " + ec.message() : std::string("; removed"));
  }
  if (replace && !earlier.empty()) {
    logInfo("--force: removed ", earlier.size(), " output(s) of an earlier run from ", dir_);
  }
  started_utc_ = utcNow();
  run_id_ = utcStamp("%Y%m%dT%H%M%SZ") + "-" + pid;
}

RunFolder::~RunFolder() {
  // The lock file stays: removing it would let a run that opened it just before lock an
  // unlinked file while a third creates a new one.
  if (lock_fd_ >= 0) ::close(lock_fd_);
}

}  // namespace emf::pipeline
