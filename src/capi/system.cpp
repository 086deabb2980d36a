// The synchronous C API: create/destroy, intrinsics, per-frame processing, objects, stats,
// meshes and renders of one emf_system.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <type_traits>

#include "capi/firewall.h"
#include "capi/system_impl.h"
#include "common/error.h"
#include "emf/emf.h"
#include "io/ply.h"
#include "map/mesh.h"
#include "map/volume_host_access.h"

namespace emf::capi {
namespace {

void copyString(char* dst, size_t size, const std::string& src) {
  std::strncpy(dst, src.c_str(), size - 1);
  dst[size - 1] = '\0';
}

emf_object_state toCState(pipeline::ObjectState state) {
  switch (state) {
    case pipeline::ObjectState::kTracked:
      return EMF_OBJECT_TRACKED;
    case pipeline::ObjectState::kLost:
      return EMF_OBJECT_LOST;
    case pipeline::ObjectState::kInvisible:
      return EMF_OBJECT_INVISIBLE;
    case pipeline::ObjectState::kDeleted:
      return EMF_OBJECT_DELETED;
    case pipeline::ObjectState::kDormant:
      return EMF_OBJECT_DORMANT;
  }
  return EMF_OBJECT_TRACKED;
}

std::string frameName(const emf_system& system) {
  return "frame " + std::to_string(system.slam ? system.slam->framesProcessed() : 0);
}

/// Checks an image view of a frame: struct_size, data, size, stride. Returns the row stride.
size_t checkImage(const emf_image& image, const char* name, int bytes_per_pixel,
                  const std::string& frame) {
  if (image.struct_size < sizeof(emf_image)) {
    throw InvalidArgument(frame + ": " + name + ".struct_size is " +
                          std::to_string(image.struct_size) + ", expected at least " +
                          std::to_string(sizeof(emf_image)) +
                          " (set it to sizeof(emf_image) or use emf_frame_init)");
  }
  if (!image.data) throw InvalidArgument(frame + ": " + name + ".data is NULL");
  if (image.width <= 0 || image.height <= 0) {
    throw InvalidArgument(frame + ": " + name + " size " + std::to_string(image.width) + "x" +
                          std::to_string(image.height) + " is not positive");
  }
  const size_t row = static_cast<size_t>(image.width) * static_cast<size_t>(bytes_per_pixel);
  if (image.stride_bytes != 0 && image.stride_bytes < row) {
    throw InvalidArgument(frame + ": " + name + ".stride_bytes " +
                          std::to_string(image.stride_bytes) + " is smaller than a row (" +
                          std::to_string(row) + " bytes)");
  }
  return image.stride_bytes ? image.stride_bytes : row;
}

/// The caller's depth as CV_32F metres, NaN = invalid.
cv::Mat depthMetres(const emf_frame& f, const core::Intrinsics& k, const std::string& frame) {
  const emf_image& d = f.depth;
  if (d.struct_size >= sizeof(emf_image) && d.format != EMF_PIXEL_DEPTH_U16 &&
      d.format != EMF_PIXEL_DEPTH_F32) {
    throw InvalidArgument(frame + ": depth.format " + std::to_string(static_cast<int>(d.format)) +
                          " is not a depth format: use EMF_PIXEL_DEPTH_U16 (with depth_scale) "
                          "or EMF_PIXEL_DEPTH_F32");
  }
  const bool u16 = d.format == EMF_PIXEL_DEPTH_U16;
  const size_t stride = checkImage(d, "depth", u16 ? 2 : 4, frame);
  if (d.width != k.width || d.height != k.height) {
    throw InvalidArgument(frame + ": depth is " + std::to_string(d.width) + "x" +
                          std::to_string(d.height) + " but the intrinsics are " +
                          std::to_string(k.width) + "x" + std::to_string(k.height) +
                          ": pass depth of the size given to emf_system_set_intrinsics");
  }
  if (u16 && !(f.depth_scale > 0 && std::isfinite(f.depth_scale))) {
    throw InvalidArgument(frame + ": depth_scale " + std::to_string(f.depth_scale) +
                          " must be a positive number of uint16 units per metre (e.g. 1000)");
  }
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cv::Mat out(d.height, d.width, CV_32FC1);
  const auto* base = static_cast<const unsigned char*>(d.data);
  const float inv_scale = u16 ? static_cast<float>(1.0 / f.depth_scale) : 1.0f;
  for (int y = 0; y < d.height; ++y) {
    float* dst = out.ptr<float>(y);
    const unsigned char* row = base + static_cast<size_t>(y) * stride;
    for (int x = 0; x < d.width; ++x) {
      if (u16) {
        uint16_t v;
        std::memcpy(&v, row + 2 * static_cast<size_t>(x), sizeof(v));
        dst[x] = v == 0 ? nan : static_cast<float>(v) * inv_scale;
      } else {
        float v;
        std::memcpy(&v, row + 4 * static_cast<size_t>(x), sizeof(v));
        dst[x] = (std::isfinite(v) && v > 0.0f) ? v : nan;
      }
    }
  }
  return out;
}

/// The caller's colour as CV_8UC3 BGR, or empty when color.data is NULL.
cv::Mat colorBgr(const emf_frame& f, const std::string& frame) {
  const emf_image& c = f.color;
  if (!c.data) return cv::Mat();
  if (c.struct_size >= sizeof(emf_image) && c.format != EMF_PIXEL_BGR8 &&
      c.format != EMF_PIXEL_RGB8) {
    throw InvalidArgument(frame + ": color.format " + std::to_string(static_cast<int>(c.format)) +
                          " is not supported: use EMF_PIXEL_BGR8 or EMF_PIXEL_RGB8, or set "
                          "color.data to NULL");
  }
  const size_t stride = checkImage(c, "color", 3, frame);
  const cv::Mat view(c.height, c.width, CV_8UC3, const_cast<void*>(c.data), stride);
  cv::Mat out;
  if (c.format == EMF_PIXEL_RGB8) {
    cv::cvtColor(view, out, cv::COLOR_RGB2BGR);
  } else {
    view.copyTo(out);
  }
  return out;
}

void requireSlam(const emf_system& system, const char* function) {
  if (!system.slam) {
    (void)function;  // the firewall prefixes the message with the function
    throw StateError("the system has no intrinsics yet: call emf_system_set_intrinsics first");
  }
}

/// The arrays of a mesh handed out, filled straight from the extraction (a MeshSink): the mesh
/// exists once, in the caller's layout.
struct MeshArrays : public map::MeshSink {
  std::vector<float> positions, normals;
  std::vector<uint32_t> indices;

  void addVertices(const Eigen::Vector3f* p, const Eigen::Vector3f* n, size_t count) override {
    for (size_t i = 0; i < count; ++i) {
      positions.insert(positions.end(), p[i].data(), p[i].data() + 3);
      normals.insert(normals.end(), n[i].data(), n[i].data() + 3);
    }
  }
  void addTriangles(const Eigen::Vector3i* t, size_t count) override {
    for (size_t i = 0; i < count; ++i) {
      for (int c = 0; c < 3; ++c) indices.push_back(static_cast<uint32_t>(t[i][c]));
    }
  }
};

/// A mesh handed out: the struct the caller holds, first, and its arrays (POD, so the emf_mesh*
/// converts back to the block).
struct MeshBlock {
  emf_mesh mesh;
  MeshArrays* arrays;
};
static_assert(std::is_standard_layout<MeshBlock>::value, "emf_mesh* must convert to MeshBlock*");

const map::Volume& volumeOf(const emf_system& system, int32_t volume_id, const char* function) {
  requireSlam(system, function);
  const map::Volume* volume = system.slam->volume(volume_id);
  if (!volume) {
    throw NotFoundError("no volume with id " + std::to_string(volume_id) +
                        " (0 = background; object ids come from emf_system_get_objects)");
  }
  return *volume;
}

/// The background's mesh includes the surface its moving grid left behind (map.follow_camera).
void extract(const emf_system& system, int32_t volume_id, const char* function,
             map::MeshSink& sink) {
  const map::Volume& volume = volumeOf(system, volume_id, function);
  if (volume_id == 0) return system.slam->extractBackgroundMesh(sink);
  const map::VolumeHostAccess access(volume);
  map::extractMesh(access.view(), access.T_world_volume(), map::MeshOptions(), sink);
}

/// Streamed into the file: the mesh is never held in memory as a whole.
void saveMesh(const emf_system& system, int32_t volume_id, const std::string& path,
              const char* function) {
  volumeOf(system, volume_id, function);  // checks the id before the file is created
  io::PlyWriter ply(path, true);
  extract(system, volume_id, function, ply);
  ply.commit();
}

}  // namespace

bool apiVersionSupported(uint32_t caller) {
  const uint32_t major = caller / 10000, minor = (caller / 100) % 100;
  return major == EMF_VERSION_MAJOR && minor <= EMF_VERSION_MINOR;
}

Config loadConfig(const char* file, const char* yaml) {
  Config config;
  if (file) config = Config::loadFile(file);
  if (yaml) config.merge(yaml, "<config_yaml>");
  config.validate();
  return config;
}

void requireIdle(const emf_system& system, const char* function) {
  if (!system.owner) return;
  const runtime::RuntimeState s = system.owner->state();
  if (s == runtime::RuntimeState::kRunning || s == runtime::RuntimeState::kSensorError) {
    (void)function;
    throw StateError(
        "the system belongs to a running runtime: call this after the end of the "
        "stream (EMF_ERROR_END_OF_STREAM) or after emf_runtime_stop");
  }
}

emf_pose toCPose(const Eigen::Isometry3d& T) {
  emf_pose p;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) p.m[4 * r + c] = T.matrix()(r, c);
  }
  return p;
}

Eigen::Isometry3d fromCPose(const emf_pose& pose) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) T.matrix()(r, c) = pose.m[4 * r + c];
  }
  return T;
}

emf_object_info toObjectInfo(const pipeline::ObjectOutcome& o) {
  emf_object_info info;
  std::memset(&info, 0, sizeof(info));
  info.struct_size = sizeof(info);
  info.id = o.id;
  copyString(info.class_name, sizeof(info.class_name), o.class_name);
  info.state = toCState(o.state);
  info.T_world_object = toCPose(o.T_world_object);
  info.T_object_camera = toCPose(o.T_object_camera);
  info.existence = o.existence;
  info.first_frame = o.first_frame;
  info.last_frame = o.last_frame;
  return info;
}

emf_status writeObjects(const std::vector<pipeline::ObjectOutcome>& objects,
                        emf_object_info* objects_out, int32_t capacity, int32_t* count,
                        const char* function) {
  if (capacity < 0) {
    return fail(EMF_ERROR_INVALID_ARGUMENT,
                std::string(function) + ": capacity " + std::to_string(capacity) + " is negative");
  }
  if (capacity > 0) {
    const emf_status s = checkStruct(objects_out, objects_out ? objects_out[0].struct_size : 0,
                                     sizeof(emf_object_info), "emf_object_info", function);
    if (s != EMF_OK) return s;
    const size_t stride = objects_out[0].struct_size;
    const size_t n = std::min(static_cast<size_t>(capacity), objects.size());
    auto* base = reinterpret_cast<unsigned char*>(objects_out);
    for (size_t i = 0; i < n; ++i) {
      emf_object_info info = toObjectInfo(objects[i]);
      info.struct_size = stride;
      std::memcpy(base + i * stride, &info, sizeof(info));
    }
  }
  if (count) *count = static_cast<int32_t>(objects.size());
  return EMF_OK;
}

}  // namespace emf::capi

using emf::capi::fail;
using emf::capi::guard;

extern "C" {

EMF_API void emf_system_options_init(emf_system_options* options) {
  if (!options) return;
  std::memset(options, 0, sizeof(*options));
  options->struct_size = sizeof(*options);
  options->api_version = EMF_API_VERSION;
}

EMF_API void emf_frame_init(emf_frame* frame) {
  if (!frame) return;
  std::memset(frame, 0, sizeof(*frame));
  frame->struct_size = sizeof(*frame);
  frame->depth.struct_size = sizeof(emf_image);
  frame->depth.format = EMF_PIXEL_DEPTH_U16;
  frame->color.struct_size = sizeof(emf_image);
  frame->color.format = EMF_PIXEL_BGR8;
  frame->depth_scale = 1000.0;
}

EMF_API emf_status emf_system_create(const emf_system_options* options, emf_system** out) {
  return guard("emf_system_create", [&]() -> emf_status {
    if (!out) return fail(EMF_ERROR_INVALID_ARGUMENT, "emf_system_create: out is NULL");
    *out = nullptr;
    const emf_status s = emf::capi::checkStruct(
        options, options ? options->struct_size : 0,
        offsetof(emf_system_options, config_yaml) + sizeof(options->config_yaml),
        "emf_system_options", "emf_system_create");
    if (s != EMF_OK) return s;
    if (!emf::capi::apiVersionSupported(options->api_version)) {
      return fail(EMF_ERROR_VERSION_MISMATCH, "emf_system_create: caller compiled against API " +
                                                  std::to_string(options->api_version) +
                                                  ", library is " + std::to_string(EMF_VERSION) +
                                                  " (same major, minor <= library's required)");
    }
    auto sys = std::make_unique<emf_system>();
    sys->config = emf::capi::loadConfig(options->config_file, options->config_yaml);
    sys->cl = std::make_unique<emf::cl::Context>(sys->config.cl);
    *out = sys.release();
    return EMF_OK;
  });
}

EMF_API void emf_system_destroy(emf_system* system) {
  if (!system || system->owner) return;  // a runtime's system is destroyed with the runtime
  try {
    delete system;
  } catch (...) {
    // Destructors do not throw; nothing may cross the boundary regardless.
  }
}

EMF_API emf_status emf_system_get_info(const emf_system* system, emf_system_info* info) {
  return guard("emf_system_get_info", [&]() -> emf_status {
    if (!system) return fail(EMF_ERROR_INVALID_ARGUMENT, "emf_system_get_info: system is NULL");
    const emf_status s =
        emf::capi::checkStruct(info, info ? info->struct_size : 0, sizeof(emf_system_info),
                               "emf_system_info", "emf_system_get_info");
    if (s != EMF_OK) return s;
    const auto& d = system->cl->device();
    emf::capi::copyString(info->device_name, sizeof(info->device_name), d.device_name);
    emf::capi::copyString(info->platform_name, sizeof(info->platform_name), d.platform_name);
    info->device_is_fallback = system->cl->selection().fallback ? 1 : 0;
    return EMF_OK;
  });
}

EMF_API emf_status emf_system_set_intrinsics(emf_system* system, const emf_intrinsics* intrinsics) {
  return guard("emf_system_set_intrinsics", [&]() -> emf_status {
    const char* fn = "emf_system_set_intrinsics";
    if (!system) return fail(EMF_ERROR_INVALID_ARGUMENT, std::string(fn) + ": system is NULL");
    if (!intrinsics) {
      return fail(EMF_ERROR_INVALID_ARGUMENT, std::string(fn) + ": intrinsics is NULL");
    }
    if (system->owner) {
      return fail(EMF_ERROR_STATE, std::string(fn) +
                                       ": the system belongs to a runtime, which sets the "
                                       "intrinsics from its source");
    }
    if (system->slam) {
      return fail(EMF_ERROR_STATE, std::string(fn) +
                                       ": intrinsics are already set; create a new system for "
                                       "another camera");
    }
    const emf_intrinsics& k = *intrinsics;
    if (!(k.fx > 0 && k.fy > 0 && std::isfinite(k.fx) && std::isfinite(k.fy) &&
          std::isfinite(k.cx) && std::isfinite(k.cy) && k.width > 0 && k.height > 0)) {
      return fail(EMF_ERROR_INVALID_ARGUMENT,
                  std::string(fn) + ": intrinsics fx=" + std::to_string(k.fx) +
                      " fy=" + std::to_string(k.fy) + " cx=" + std::to_string(k.cx) +
                      " cy=" + std::to_string(k.cy) + " width=" + std::to_string(k.width) +
                      " height=" + std::to_string(k.height) +
                      ": focal lengths and the image size must be positive, all finite");
    }
    emf::core::Intrinsics in;
    in.fx = k.fx;
    in.fy = k.fy;
    in.cx = k.cx;
    in.cy = k.cy;
    in.width = k.width;
    in.height = k.height;
    system->slam = std::make_unique<emf::pipeline::SlamSystem>(*system->cl, system->config, in);
    return EMF_OK;
  });
}

EMF_API emf_status emf_system_process_frame(emf_system* system, const emf_frame* frame,
                                            emf_frame_result* result) {
  return guard("emf_system_process_frame", [&]() -> emf_status {
    const char* fn = "emf_system_process_frame";
    if (!system) return fail(EMF_ERROR_INVALID_ARGUMENT, std::string(fn) + ": system is NULL");
    emf_status s = emf::capi::checkStruct(frame, frame ? frame->struct_size : 0, sizeof(emf_frame),
                                          "emf_frame", fn);
    if (s != EMF_OK) return s;
    if (result) {
      s = emf::capi::checkStruct(result, result->struct_size, sizeof(emf_frame_result),
                                 "emf_frame_result", fn);
      if (s != EMF_OK) return s;
    }
    if (system->owner) {
      return fail(EMF_ERROR_STATE, std::string(fn) +
                                       ": the system belongs to a runtime, which feeds it "
                                       "frames from its source");
    }
    emf::capi::requireSlam(*system, fn);
    const std::string name = emf::capi::frameName(*system);
    if (!std::isfinite(frame->timestamp)) {
      return fail(EMF_ERROR_INVALID_ARGUMENT,
                  std::string(fn) + ": " + name + ": timestamp " +
                      std::to_string(frame->timestamp) +
                      " is not a finite number: pass sensor timestamps in seconds, increasing");
    }
    if (system->has_frame && !(frame->timestamp > system->last_timestamp)) {
      return fail(EMF_ERROR_INVALID_ARGUMENT,
                  std::string(fn) + ": " + name + ": timestamp " +
                      std::to_string(frame->timestamp) + " does not increase (previous " +
                      std::to_string(system->last_timestamp) +
                      "): pass sensor timestamps in seconds, increasing");
    }
    emf::core::Frame f;
    f.index = system->slam->framesProcessed();
    f.timestamp = frame->timestamp;
    f.rgb_timestamp = frame->timestamp;
    char stamp[32];
    std::snprintf(stamp, sizeof(stamp), "%.6f", frame->timestamp);
    f.timestamp_text = stamp;
    f.depth = emf::capi::depthMetres(*frame, system->slam->intrinsics(), name);
    f.color = emf::capi::colorBgr(*frame, name);

    const auto t0 = std::chrono::steady_clock::now();
    emf::pipeline::FrameOutcome o = system->slam->process(f);
    const auto t1 = std::chrono::steady_clock::now();
    system->has_frame = true;
    system->last_timestamp = frame->timestamp;
    system->last_objects = o.objects;
    if (result) {
      emf_frame_result r;
      std::memset(&r, 0, sizeof(r));
      r.struct_size = sizeof(r);
      r.frame_index = o.index;
      r.source_index = o.index;
      r.timestamp = o.timestamp;
      r.T_world_camera = emf::capi::toCPose(o.T_world_camera);
      r.tracking_lost = o.lost ? 1 : 0;
      r.object_count = static_cast<int32_t>(o.objects.size());
      r.processing_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
      const emf::map::PoolStats p = system->slam->pool().stats();
      r.pool_blocks_used = p.used_slots;
      r.pool_blocks_dropped = p.dropped_blocks;
      emf::capi::copyOut(r, result);
    }
    return EMF_OK;
  });
}

EMF_API emf_status emf_system_get_objects(const emf_system* system, emf_object_info* objects,
                                          int32_t capacity, int32_t* count) {
  return guard("emf_system_get_objects", [&]() -> emf_status {
    const char* fn = "emf_system_get_objects";
    if (!system) return fail(EMF_ERROR_INVALID_ARGUMENT, std::string(fn) + ": system is NULL");
    if (!count) return fail(EMF_ERROR_INVALID_ARGUMENT, std::string(fn) + ": count is NULL");
    emf::capi::requireIdle(*system, fn);
    return emf::capi::writeObjects(system->last_objects, objects, capacity, count, fn);
  });
}

EMF_API emf_status emf_system_get_stats(const emf_system* system, emf_stats* stats) {
  return guard("emf_system_get_stats", [&]() -> emf_status {
    const char* fn = "emf_system_get_stats";
    if (!system) return fail(EMF_ERROR_INVALID_ARGUMENT, std::string(fn) + ": system is NULL");
    const emf_status s = emf::capi::checkStruct(
        stats, stats ? stats->struct_size : 0, offsetof(emf_stats, detector_runs), "emf_stats", fn);
    if (s != EMF_OK) return s;
    emf::capi::requireIdle(*system, fn);
    emf_stats out;
    std::memset(&out, 0, sizeof(out));
    out.struct_size = sizeof(out);
    if (system->slam) {
      out.frames_processed = system->slam->framesProcessed();
      out.frames_lost = system->slam->framesLost();
      const emf::map::PoolStats p = system->slam->pool().stats();
      out.pool_blocks_total = p.capacity_slots;
      out.pool_blocks_used = p.used_slots;
      out.pool_blocks_dropped = p.dropped_blocks;
      out.pool_bytes = static_cast<int64_t>(p.pool_bytes);
      const emf::pipeline::DetectorStats d = system->slam->detectorStats();
      out.detector_runs = d.runs;
      out.detector_failures = d.failures;
      out.detector_crashes = d.crashes;
      out.detector_timeouts = d.timeouts;
      out.detector_restarts = d.restarts;
    }
    emf::capi::copyOut(out, stats);
    return EMF_OK;
  });
}

EMF_API emf_status emf_system_extract_mesh(emf_system* system, int32_t volume_id, emf_mesh** out) {
  return guard("emf_system_extract_mesh", [&]() -> emf_status {
    const char* fn = "emf_system_extract_mesh";
    if (!out) return fail(EMF_ERROR_INVALID_ARGUMENT, std::string(fn) + ": out is NULL");
    *out = nullptr;
    if (!system) return fail(EMF_ERROR_INVALID_ARGUMENT, std::string(fn) + ": system is NULL");
    emf::capi::requireIdle(*system, fn);
    auto arrays = std::make_unique<emf::capi::MeshArrays>();
    emf::capi::extract(*system, volume_id, fn, *arrays);
    const size_t nv = arrays->positions.size() / 3, nt = arrays->indices.size() / 3;
    if (nv > static_cast<size_t>(std::numeric_limits<int32_t>::max()) ||
        nt > static_cast<size_t>(std::numeric_limits<int32_t>::max())) {
      throw emf::ResourceError("the mesh has " + std::to_string(nv) + " vertices and " +
                               std::to_string(nt) +
                               " triangles, more than emf_mesh counts (int32)");
    }
    for (auto* v : {&arrays->positions, &arrays->normals}) v->reserve(1);  // never NULL
    arrays->indices.reserve(1);
    auto block = std::make_unique<emf::capi::MeshBlock>();
    block->mesh.struct_size = sizeof(emf_mesh);
    block->mesh.vertex_count = static_cast<int32_t>(nv);
    block->mesh.positions = arrays->positions.data();
    block->mesh.normals = arrays->normals.data();
    block->mesh.triangle_count = static_cast<int32_t>(nt);
    block->mesh.indices = arrays->indices.data();
    block->arrays = arrays.release();
    *out = &block.release()->mesh;
    return EMF_OK;
  });
}

EMF_API void emf_mesh_destroy(emf_mesh* mesh) {
  if (!mesh) return;
  auto* block = reinterpret_cast<emf::capi::MeshBlock*>(mesh);
  delete block->arrays;
  delete block;
}

EMF_API emf_status emf_system_save_mesh(emf_system* system, int32_t volume_id, const char* path) {
  return guard("emf_system_save_mesh", [&]() -> emf_status {
    const char* fn = "emf_system_save_mesh";
    if (!system) return fail(EMF_ERROR_INVALID_ARGUMENT, std::string(fn) + ": system is NULL");
    if (!path || !*path) {
      return fail(EMF_ERROR_INVALID_ARGUMENT, std::string(fn) + ": path is NULL or empty");
    }
    emf::capi::requireIdle(*system, fn);
    emf::capi::saveMesh(*system, volume_id, path, fn);
    return EMF_OK;
  });
}

EMF_API emf_status emf_system_get_association(const emf_system* system, int32_t volume_id,
                                              float* q) {
  return guard("emf_system_get_association", [&]() -> emf_status {
    const char* fn = "emf_system_get_association";
    if (!system) return fail(EMF_ERROR_INVALID_ARGUMENT, std::string(fn) + ": system is NULL");
    if (!q) return fail(EMF_ERROR_INVALID_ARGUMENT, std::string(fn) + ": q is NULL");
    emf::capi::requireIdle(*system, fn);
    emf::capi::requireSlam(*system, fn);
    if (system->slam->framesProcessed() == 0) {
      return fail(EMF_ERROR_STATE, std::string(fn) + ": no frame processed yet");
    }
    const emf::pipeline::SlamSystem::Associations a = system->slam->associations();
    for (size_t i = 0; i < a.ids.size(); ++i) {
      if (a.ids[i] != volume_id) continue;
      cv::Mat m = a.q[i];
      if (!m.isContinuous()) m = m.clone();
      std::memcpy(q, m.ptr<float>(), m.total() * sizeof(float));
      return EMF_OK;
    }
    return fail(EMF_ERROR_NOT_FOUND,
                std::string(fn) + ": volume " + std::to_string(volume_id) +
                    (a.ids.empty() ? " has no association map: no E-step ran in the last frame "
                                     "(no object alive and no detection)"
                                   : " was not in the last frame's E-step (deleted, dormant or "
                                     "never an object)"));
  });
}

EMF_API emf_status emf_system_render(emf_system* system, const emf_pose* T_world_camera,
                                     float* depth_m, int32_t* volume_ids) {
  return guard("emf_system_render", [&]() -> emf_status {
    const char* fn = "emf_system_render";
    if (!system) return fail(EMF_ERROR_INVALID_ARGUMENT, std::string(fn) + ": system is NULL");
    emf::capi::requireIdle(*system, fn);
    emf::capi::requireSlam(*system, fn);
    const emf::core::Intrinsics& k = system->slam->intrinsics();
    if (!system->raycaster) {
      system->raycaster =
          std::make_unique<emf::map::RayCaster>(*system->cl, system->config.map, k.width, k.height);
    }
    if (T_world_camera) {
      const Eigen::Map<const Eigen::Matrix<double, 3, 4, Eigen::RowMajor>> m(T_world_camera->m);
      const Eigen::Matrix3d R = m.leftCols<3>();
      const double orthogonality =
          (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
      if (!m.allFinite() || !(orthogonality < 1e-4) || !(R.determinant() > 0)) {
        return fail(
            EMF_ERROR_INVALID_ARGUMENT,
            std::string(fn) + ": T_world_camera is not a rigid transform (max |R^T R - I| " +
                std::to_string(orthogonality) + ", det R " + std::to_string(R.determinant()) +
                "): pass a rotation matrix and a translation in metres, row-major 3x4");
      }
    }
    const Eigen::Isometry3d pose =
        T_world_camera ? emf::capi::fromCPose(*T_world_camera) : system->slam->T_world_camera();
    system->raycaster->render(system->slam->renderItems(), k, pose);
    cv::Mat depth, ids;
    system->raycaster->download(depth_m ? &depth : nullptr, nullptr, volume_ids ? &ids : nullptr);
    const size_t n = static_cast<size_t>(k.width) * static_cast<size_t>(k.height);
    if (depth_m) {
      if (!depth.isContinuous()) depth = depth.clone();
      std::memcpy(depth_m, depth.ptr<float>(), n * sizeof(float));
    }
    if (volume_ids) {
      if (!ids.isContinuous()) ids = ids.clone();
      std::memcpy(volume_ids, ids.ptr<int32_t>(), n * sizeof(int32_t));
    }
    return EMF_OK;
  });
}

}  // extern "C"
