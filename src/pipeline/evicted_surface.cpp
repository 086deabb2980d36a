#include "pipeline/evicted_surface.h"

#include "map/volume_follow.h"
#include "map/volume_host_access.h"

namespace emf::pipeline {

EvictedSurface::EvictedSurface(std::string folder)
    : folder_(std::move(folder)), worker_([this] { run(); }) {}

EvictedSurface::~EvictedSurface() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  worker_.join();
}

void EvictedSurface::rethrow() {
  if (error_) {
    std::exception_ptr e = error_;
    error_ = nullptr;
    std::rethrow_exception(e);
  }
}

void EvictedSurface::add(const map::Volume& volume, const Eigen::Vector3i& blocks) {
  auto job = std::make_unique<Job>();
  const map::Volume::BlockFilter keep = map::leavingMeshBlocks(blocks, volume.spec().dims_blocks);
  job->blocks = map::copyBlocks(map::VolumeHostAccess(volume, keep), keep);
  job->move = blocks;
  std::unique_lock<std::mutex> lock(mutex_);
  rethrow();
  if (!spool_) spool_ = std::make_unique<io::MeshSpool>(folder_);
  changed_.wait(lock, [this] { return pending_.size() < kMaxPending || error_; });
  rethrow();
  pending_.push_back(std::move(job));
  changed_.notify_all();
}

void EvictedSurface::waitIdle(std::unique_lock<std::mutex>& lock) {
  changed_.wait(lock, [this] { return (pending_.empty() && !busy_) || error_; });
}

size_t EvictedSurface::replay(map::MeshSink& sink) {
  std::unique_lock<std::mutex> lock(mutex_);
  waitIdle(lock);
  rethrow();
  if (!spool_) return 0;
  spool_->replay(sink);
  return spool_->vertexCount();
}

void EvictedSurface::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    changed_.wait(lock, [this] { return stop_ || !pending_.empty(); });
    if (pending_.empty()) return;  // stopping, nothing left
    std::unique_ptr<Job> job = std::move(pending_.front());
    pending_.pop_front();
    busy_ = true;
    io::MeshSpool* spool = spool_.get();  // created before the first job was queued
    lock.unlock();
    std::exception_ptr failed;
    try {
      spool->beginPart();
      map::extractLeavingMesh(job->blocks.view(), job->blocks.T_world_volume, job->move, *spool);
    } catch (...) {
      failed = std::current_exception();
    }
    job.reset();
    lock.lock();
    busy_ = false;
    if (failed && !error_) error_ = failed;
    changed_.notify_all();
  }
}

}  // namespace emf::pipeline
