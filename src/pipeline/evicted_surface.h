// The surface a background following the camera leaves behind (map.follow_camera), meshed off
// the SLAM thread. At a move the SLAM thread copies the leaving blocks and the layer next to
// them (map::leavingMeshBlocks: a few hundred blocks, 2 KiB each) and hands the copy over; a
// worker thread meshes it (map::extractLeavingMesh) into an io::MeshSpool on disk. replay()
// waits for the worker to finish what it was given, then streams the whole surface.
//
// Threads: add() and replay() from the SLAM thread (one caller at a time); the worker owns the
// spool while jobs are pending. At most kMaxPending copies wait; add() blocks beyond that. An
// error of the worker (disk full) is rethrown by the next add() or replay().
#pragma once

#include <condition_variable>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "io/mesh_spool.h"
#include "map/volume.h"

namespace emf::pipeline {

class EvictedSurface {
 public:
  /// Copies waiting to be meshed before add() blocks.
  static constexpr size_t kMaxPending = 8;

  /// The spool's temporary files go to `folder` (created on the first add()).
  explicit EvictedSurface(std::string folder);
  /// Finishes the pending work and stops the worker.
  ~EvictedSurface();
  EvictedSurface(const EvictedSurface&) = delete;
  EvictedSurface& operator=(const EvictedSurface&) = delete;

  /// Queues the mesh of what `volume.shift(blocks)` is about to take out of the grid: copies
  /// the blocks that mesh reads now (call it before the shift). Throws IoError when the spool
  /// cannot be created or the worker failed.
  void add(const map::Volume& volume, const Eigen::Vector3i& blocks);
  /// Waits for the pending meshes, then streams every part to `sink` (indices from 0). Returns
  /// the vertices streamed.
  size_t replay(map::MeshSink& sink);

 private:
  struct Job {
    map::VolumeHostData blocks;  // the leaving blocks and the next layer, before the shift
    Eigen::Vector3i move;
  };
  void run();
  void waitIdle(std::unique_lock<std::mutex>& lock);
  void rethrow();

  std::string folder_;
  std::unique_ptr<io::MeshSpool> spool_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<std::unique_ptr<Job>> pending_;
  bool busy_ = false, stop_ = false;
  std::exception_ptr error_;
  std::thread worker_;
};

}  // namespace emf::pipeline
