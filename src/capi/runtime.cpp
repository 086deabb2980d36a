// The runtime C API: emf_runtime wraps a runtime::Runtime around an emf_system whose
// SlamSystem is fed by the runtime's SLAM thread.
#include <condition_variable>
#include <cstddef>
#include <cstring>
#include <memory>
#include <mutex>
#include <vector>

#include "capi/firewall.h"
#include "capi/system_impl.h"
#include "common/error.h"
#include "core/frame_source.h"
#include "emf/emf.h"
#include "sources/open_source.h"

namespace emf::capi {
namespace {

/// Runs the system's SlamSystem on the SLAM thread and keeps the last objects for
/// emf_system_get_objects (read only while the runtime is not running).
class SystemProcessor : public runtime::FrameProcessor {
 public:
  explicit SystemProcessor(emf_system& system) : system_(system), slam_(*system.slam) {}
  pipeline::FrameOutcome process(const core::Frame& frame) override {
    pipeline::FrameOutcome o = system_.slam->process(frame);
    system_.last_objects = o.objects;
    system_.has_frame = true;
    system_.last_timestamp = o.timestamp;
    return o;
  }
  runtime::PoolCounters pool() const override { return slam_.pool(); }

 private:
  emf_system& system_;
  runtime::SlamProcessor slam_;
};

emf_frame_result toCResult(const runtime::RuntimeResult& r) {
  emf_frame_result out;
  std::memset(&out, 0, sizeof(out));
  out.struct_size = sizeof(out);
  out.frame_index = r.frame_index;
  out.source_index = r.source_index;
  out.timestamp = r.timestamp;
  out.T_world_camera = toCPose(r.T_world_camera);
  out.tracking_lost = r.lost ? 1 : 0;
  out.object_count = static_cast<int32_t>(r.objects.size());
  out.processing_ms = r.processing_ms;
  out.latency_ms = r.latency_ms;
  out.frames_dropped = r.counters.dropped;
  out.pool_blocks_used = r.counters.pool.blocks_used;
  out.pool_blocks_dropped = r.counters.pool.blocks_dropped;
  return out;
}

}  // namespace
}  // namespace emf::capi

/// The object behind emf_runtime. Members are destroyed in reverse order: the runtime (joining
/// its threads) before the processor and the system it uses.
struct emf_runtime {
  emf_system system;
  std::unique_ptr<emf::capi::SystemProcessor> processor;
  emf_result_callback callback = nullptr;
  void* user_data = nullptr;
  std::unique_ptr<emf::runtime::Runtime> runtime;
  // Calls other threads may make while the controlling thread destroys (poll, get_stats):
  // emf_runtime_destroy stops the runtime, which ends a blocked poll, then waits for 0.
  mutable std::mutex calls_mutex;
  mutable std::condition_variable calls_cv;
  mutable int calls = 0;
};

namespace {
/// Counts a thread-safe call on `rt` for its whole duration (see emf_runtime::calls).
class CallScope {
 public:
  explicit CallScope(const emf_runtime& rt) : rt_(rt) {
    const std::lock_guard<std::mutex> lock(rt_.calls_mutex);
    ++rt_.calls;
  }
  ~CallScope() {
    const std::lock_guard<std::mutex> lock(rt_.calls_mutex);
    if (--rt_.calls == 0) rt_.calls_cv.notify_all();
  }
  CallScope(const CallScope&) = delete;
  CallScope& operator=(const CallScope&) = delete;

 private:
  const emf_runtime& rt_;
};
}  // namespace

using emf::capi::fail;
using emf::capi::guard;

extern "C" {

EMF_API void emf_runtime_options_init(emf_runtime_options* options) {
  if (!options) return;
  std::memset(options, 0, sizeof(*options));
  options->struct_size = sizeof(*options);
  options->api_version = EMF_API_VERSION;
}

EMF_API emf_status emf_runtime_create(const emf_runtime_options* options, emf_runtime** out) {
  return guard("emf_runtime_create", [&]() -> emf_status {
    const char* fn = "emf_runtime_create";
    if (!out) return fail(EMF_ERROR_INVALID_ARGUMENT, std::string(fn) + ": out is NULL");
    *out = nullptr;
    const emf_status s =
        emf::capi::checkStruct(options, options ? options->struct_size : 0,
                               sizeof(emf_runtime_options), "emf_runtime_options", fn);
    if (s != EMF_OK) return s;
    if (!emf::capi::apiVersionSupported(options->api_version)) {
      return fail(EMF_ERROR_VERSION_MISMATCH, std::string(fn) + ": caller compiled against API " +
                                                  std::to_string(options->api_version) +
                                                  ", library is " + std::to_string(EMF_VERSION) +
                                                  " (same major, minor <= library's required)");
    }
    auto rt = std::make_unique<emf_runtime>();
    emf_system& sys = rt->system;
    sys.config = emf::capi::loadConfig(options->config_file, options->config_yaml);
    const std::string uri = options->source_uri ? options->source_uri : sys.config.source.uri;
    if (uri.empty()) {
      return fail(EMF_ERROR_INVALID_ARGUMENT,
                  std::string(fn) + ": no source: set source_uri or the config's source.uri");
    }
    std::unique_ptr<emf::core::FrameSource> source =
        emf::sources::openSource(uri, sys.config.source);
    const emf::core::Intrinsics k = source->intrinsics();
    if (!k.valid()) {
      throw emf::IoError("source '" + uri +
                         "' reports no valid intrinsics: give them in the URI (?fx=..&fy=..&cx=.."
                         "&cy=..) or the config's source section");
    }
    sys.cl = std::make_unique<emf::cl::Context>(sys.config.cl);
    sys.slam = std::make_unique<emf::pipeline::SlamSystem>(*sys.cl, sys.config, k, uri);
    rt->processor = std::make_unique<emf::capi::SystemProcessor>(sys);
    rt->callback = options->callback;
    rt->user_data = options->user_data;
    emf::runtime::Runtime::Callback callback;
    if (rt->callback) {
      emf_runtime* self = rt.get();
      callback = [self](const emf::runtime::RuntimeResult& r) {
        const emf_frame_result result = emf::capi::toCResult(r);
        std::vector<emf_object_info> objects;
        objects.reserve(r.objects.size());
        for (const auto& o : r.objects) objects.push_back(emf::capi::toObjectInfo(o));
        self->callback(&result, objects.empty() ? nullptr : objects.data(),
                       static_cast<int32_t>(objects.size()), self->user_data);
      };
    }
    rt->runtime = std::make_unique<emf::runtime::Runtime>(std::move(source), *rt->processor,
                                                          sys.config.runtime, callback);
    sys.owner = rt->runtime.get();
    *out = rt.release();
    return EMF_OK;
  });
}

EMF_API emf_status emf_runtime_start(emf_runtime* runtime) {
  return guard("emf_runtime_start", [&]() -> emf_status {
    if (!runtime) return fail(EMF_ERROR_INVALID_ARGUMENT, "emf_runtime_start: runtime is NULL");
    runtime->runtime->start();
    return EMF_OK;
  });
}

EMF_API emf_status emf_runtime_poll(emf_runtime* runtime, int32_t timeout_ms,
                                    emf_frame_result* result, emf_object_info* objects,
                                    int32_t capacity, int32_t* count) {
  return guard("emf_runtime_poll", [&]() -> emf_status {
    const char* fn = "emf_runtime_poll";
    if (!runtime) return fail(EMF_ERROR_INVALID_ARGUMENT, std::string(fn) + ": runtime is NULL");
    if (timeout_ms < 0) {
      return fail(EMF_ERROR_INVALID_ARGUMENT,
                  std::string(fn) + ": timeout_ms " + std::to_string(timeout_ms) + " is negative");
    }
    emf_status s = EMF_OK;
    if (result) {
      s = emf::capi::checkStruct(result, result->struct_size, sizeof(emf_frame_result),
                                 "emf_frame_result", fn);
      if (s != EMF_OK) return s;
    }
    if (capacity < 0 || (capacity > 0 && !objects)) {
      return fail(EMF_ERROR_INVALID_ARGUMENT, std::string(fn) + ": objects is NULL or capacity " +
                                                  std::to_string(capacity) + " is negative");
    }
    if (capacity > 0) {
      s = emf::capi::checkStruct(objects, objects[0].struct_size, sizeof(emf_object_info),
                                 "emf_object_info", fn);
      if (s != EMF_OK) return s;
    }
    const CallScope scope(*runtime);
    emf::runtime::Runtime& rt = *runtime->runtime;
    emf::runtime::RuntimeResult r;
    switch (rt.poll(timeout_ms * 1e-3, &r)) {
      case emf::runtime::PollStatus::kResult:
        break;
      case emf::runtime::PollStatus::kTimeout:
        return fail(EMF_ERROR_TIMEOUT,
                    std::string(fn) + ": no result within " + std::to_string(timeout_ms) + " ms");
      case emf::runtime::PollStatus::kEndOfStream:
        return fail(EMF_ERROR_END_OF_STREAM,
                    std::string(fn) + ": end of stream: " + rt.describeSource() +
                        " is exhausted and every queued result was polled (" +
                        std::to_string(rt.counters().processed) + " frames processed, " +
                        std::to_string(rt.counters().results_dropped) +
                        " results dropped from the full queue: see emf_stats.results_dropped)");
      case emf::runtime::PollStatus::kSensorError:
        return fail(EMF_ERROR_DEVICE, std::string(fn) + ": " + rt.sensorError() +
                                          " (the runtime keeps retrying and resumes when the "
                                          "sensor is back; poll again)");
      case emf::runtime::PollStatus::kStopped:
        return fail(EMF_ERROR_STATE, std::string(fn) +
                                         ": the runtime was stopped and every queued result "
                                         "was polled");
      case emf::runtime::PollStatus::kFailed:
        std::rethrow_exception(rt.failure());  // mapped to its status by the firewall
    }
    if (result) emf::capi::copyOut(emf::capi::toCResult(r), result);
    return emf::capi::writeObjects(r.objects, objects, capacity, count, fn);
  });
}

EMF_API emf_status emf_runtime_stop(emf_runtime* runtime) {
  return guard("emf_runtime_stop", [&]() -> emf_status {
    if (!runtime) return fail(EMF_ERROR_INVALID_ARGUMENT, "emf_runtime_stop: runtime is NULL");
    runtime->runtime->stop();
    return EMF_OK;
  });
}

EMF_API emf_status emf_runtime_get_stats(const emf_runtime* runtime, emf_stats* stats) {
  return guard("emf_runtime_get_stats", [&]() -> emf_status {
    const char* fn = "emf_runtime_get_stats";
    if (!runtime) return fail(EMF_ERROR_INVALID_ARGUMENT, std::string(fn) + ": runtime is NULL");
    const emf_status s = emf::capi::checkStruct(
        stats, stats ? stats->struct_size : 0, offsetof(emf_stats, detector_runs), "emf_stats", fn);
    if (s != EMF_OK) return s;
    const CallScope scope(*runtime);
    const emf::runtime::RuntimeCounters c = runtime->runtime->counters();
    emf_stats out;
    std::memset(&out, 0, sizeof(out));
    out.struct_size = sizeof(out);
    out.frames_processed = c.processed;
    out.frames_lost = c.lost;
    out.pool_blocks_total = c.pool.blocks_total;
    out.pool_blocks_used = c.pool.blocks_used;
    out.pool_blocks_dropped = c.pool.blocks_dropped;
    out.pool_bytes = c.pool.bytes;
    out.frames_produced = c.produced;
    out.frames_dropped = c.dropped;
    out.results_dropped = c.results_dropped;
    out.sensor_errors = c.sensor_errors;
    out.source_frames_dropped = c.source_dropped;
    emf::capi::copyOut(out, stats);
    return EMF_OK;
  });
}

EMF_API emf_system* emf_runtime_system(emf_runtime* runtime) {
  return runtime ? &runtime->system : nullptr;
}

EMF_API void emf_runtime_destroy(emf_runtime* runtime) {
  if (!runtime) return;
  try {
    // Stopping ends every poll blocked on this runtime (EMF_ERROR_STATE); then wait until the
    // calls of other threads have left before the memory goes.
    runtime->runtime->stop();
    {
      std::unique_lock<std::mutex> lock(runtime->calls_mutex);
      runtime->calls_cv.wait(lock, [runtime] { return runtime->calls == 0; });
    }
    delete runtime;  // ~Runtime joins (done) and frees
  } catch (...) {
    // Nothing may cross the boundary.
  }
}

}  // extern "C"
