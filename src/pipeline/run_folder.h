// The output folder of one run (`emf run --out DIR`). Claimed before the first frame: created,
// checked writable, locked against a second emf process, and given a run id that run.json and
// every trajectory header carry. A folder holds one run: an earlier run's outputs there are an
// error unless the caller asks to replace them (--force), so a new run never leaves a mix of its
// files and an older run's.
#pragma once

#include <string>
#include <vector>

namespace emf::pipeline {

class RunFolder {
 public:
  /// Claims `dir` (created with its parents). Throws IoError naming the folder and what to do
  /// when it cannot be created or written, when another emf process holds it, or, unless
  /// `replace`, when it holds an earlier run's outputs (isRunOutput); with `replace` those are
  /// removed first. Temporary files a killed run left (`*.tmp-<pid>-<n>`) are removed and
  /// logged either way.
  RunFolder(std::string dir, bool replace);
  /// Releases the lock (the folder, its outputs and the lock file .emf-run.lock stay).
  ~RunFolder();
  RunFolder(const RunFolder&) = delete;
  RunFolder& operator=(const RunFolder&) = delete;

  const std::string& dir() const { return dir_; }
  /// "<UTC start time>-<pid>", e.g. "20261127T191530Z-4242".
  const std::string& runId() const { return run_id_; }
  /// Start time, ISO 8601 UTC ("2026-11-27T19:15:30Z").
  const std::string& startedUtc() const { return started_utc_; }
  /// `dir`/`name`.
  std::string path(const std::string& name) const { return dir_ + "/" + name; }
  /// Names of the files removed when the folder was claimed (earlier outputs, temporaries).
  const std::vector<std::string>& removed() const { return removed_; }

  /// True for the names an emf run (and `emf eval` into it) writes: run.json, camera.txt,
  /// background.ply, object-<id>.txt / .ply, images/, eval.json, eval.png.
  static bool isRunOutput(const std::string& name);
  /// True for a temporary file of an atomic write (`<name>.tmp-<pid>-<n>`).
  static bool isTemporary(const std::string& name);

 private:
  std::string dir_;
  std::string lock_path_;
  std::string run_id_;
  std::string started_utc_;
  std::vector<std::string> removed_;
  int lock_fd_ = -1;
};

/// Now as ISO 8601 UTC, seconds ("2026-11-27T19:15:30Z").
std::string utcNow();

}  // namespace emf::pipeline
