// The dynamic SLAM (EM loop + object lifecycle) on the synthetic presets with the simulated
// detector's detections: camera and per-object ATE against the exact ground truth.
#include <cstdlib>
#include <map>

#include "common/log.h"
#include "io/eval.h"
#include "map/mesh.h"
#include "io/frame_source.h"
#include "pipeline/slam_system.h"
#include "test_support.h"

namespace emf::pipeline {
namespace {

struct RunResult {
  io::Trajectory camera_gt, camera_est;
  std::map<int, io::Trajectory> object_gt;   // gt id -> T_object_camera (gt object frame)
  std::map<int, io::Trajectory> object_est;  // est id -> T_object_camera
  std::map<int, std::string> object_class;
  int64_t lost = 0;
};

template <typename V>
std::string fmt(const V& v) {
  char b[96];
  std::snprintf(b, sizeof(b), "%.3f %.3f %.3f", double(v.x()), double(v.y()), double(v.z()));
  return b;
}

RunResult runPreset(const std::string& uri, const Config& config) {
  cl::Context ctx(config.cl);
  auto src = io::openSource(uri, config.source);
  SlamSystem slam(ctx, config, src->intrinsics());
  RunResult r;
  io::Frame f;
  while (src->next(f)) {
    const FrameOutcome o = slam.process(f, f.detections ? &*f.detections : nullptr);
    if (std::getenv("EMF_DEBUG_Q")) {
      const auto a = slam.associations();
      for (size_t i = 0; i < a.ids.size(); ++i) {
        const cv::Mat bgm = f.instance_ids == 0;
        std::printf("frame %lld vol %d: q mass on objects %.1f, on background %.1f\n",
                    static_cast<long long>(o.index), a.ids[i],
                    cv::sum(a.q[i])[0] - cv::mean(a.q[i], bgm)[0] * cv::countNonZero(bgm),
                    cv::mean(a.q[i], bgm)[0] * cv::countNonZero(bgm));
        for (int g = 1; g <= 2; ++g) {
          const cv::Mat m = f.instance_ids == g;
          std::printf("frame %lld vol %d gt %d: mean q %.3f over %d px\n",
                      static_cast<long long>(o.index), a.ids[i], g, cv::mean(a.q[i], m)[0],
                      cv::countNonZero(m));
        }
      }
    }
    if (std::getenv("EMF_DEBUG_MESH") && o.index < 3) {
      for (const auto& ob : o.objects) {
        const map::Mesh m = map::extractMesh(slam.volume(ob.id)->download());
        Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e9), hi = -lo;
        for (const auto& v : m.vertices) {
          lo = lo.cwiseMin(v);
          hi = hi.cwiseMax(v);
        }
        std::printf("frame %lld object %d: %zu vertices, box (%s) - (%s)\n",
                    static_cast<long long>(o.index), ob.id, m.vertices.size(),
                    fmt(lo).c_str(), fmt(hi).c_str());
      }
      for (const auto& [id, T_wo] : f.T_world_object_gt) {
        std::printf("frame %lld gt %d at (%s)\n", static_cast<long long>(o.index), id,
                    fmt((*f.T_world_camera_gt).inverse() * T_wo.translation()).c_str());
      }
    }
    r.camera_gt.append(f.timestamp, *f.T_world_camera_gt);
    r.camera_est.append(f.timestamp, o.T_world_camera);
    for (const auto& [id, T_wo] : f.T_world_object_gt) {
      r.object_gt[id].append(f.timestamp, T_wo.inverse() * *f.T_world_camera_gt);
    }
    for (const auto& ob : o.objects) {
      if (ob.state != ObjectState::kTracked || ob.last_frame != o.index) continue;
      r.object_est[ob.id].append(f.timestamp, ob.T_object_camera);
      r.object_class[ob.id] = ob.class_name;
    }
  }
  if (std::getenv("EMF_DEBUG_Q")) {
    for (const auto& [gid, gt] : r.object_gt) {
      for (size_t i = 1; i < std::min<size_t>(gt.size(), 6); ++i) {
        const Eigen::Isometry3d d = gt.poses[i - 1].inverse() * gt.poses[i];
        std::printf("gt %d frame %zu: camera motion in object frame %.4f m %.3f deg\n", gid, i,
                    d.translation().norm(),
                    Eigen::AngleAxisd(d.rotation()).angle() * 180 / M_PI);
      }
    }
    for (const auto& [id, est] : r.object_est) {
      for (size_t i = 1; i < std::min<size_t>(est.size(), 6); ++i) {
        const Eigen::Isometry3d d = est.poses[i - 1].inverse() * est.poses[i];
        std::printf("est %d frame %zu: camera motion in object frame %.4f m %.3f deg\n", id, i,
                    d.translation().norm(),
                    Eigen::AngleAxisd(d.rotation()).angle() * 180 / M_PI);
      }
    }
  }
  r.lost = slam.framesLost();
  return r;
}

Config smallConfig() {
  Config c;
  c.map.memory_mb = 128;
  c.map.background_voxel_m = 0.02;
  c.map.background_resolution = 256;
  if (std::getenv("EMF_NOFREE")) c.map.free_space_full_weight = false;
  if (std::getenv("EMF_T1")) {
    c.track.coarse_levels = 0;
    c.track.max_step_scale = 1;
    c.track.early_exit_step = 0;
    c.track.lost_if_not_converged = false;
  }
  return c;
}

TEST(SlamObjects, CarsPreset) {
  const char* frames = std::getenv("EMF_OBJECTS_FRAMES");
  const std::string n = frames ? frames : "90";
  const RunResult r =
      runPreset("synth:cars?frames=" + n + "&width=" + std::string(std::getenv("EMF_W") ? std::getenv("EMF_W") : "320") + "&height=" + std::string(std::getenv("EMF_H") ? std::getenv("EMF_H") : "240") + "&seed=1" + (std::getenv("EMF_NOISE") ? std::string("&noise=") + std::getenv("EMF_NOISE") : std::string()), smallConfig());
  const double cam = io::computeAte(r.camera_gt, r.camera_est).trans_m.rmse;
  std::printf("camera ATE %.4f m, lost %lld\n", cam, static_cast<long long>(r.lost));
  for (const auto& [id, est] : r.object_est) {
    for (const auto& [gid, gt] : r.object_gt) {
      if (est.size() < 3) continue;
      const io::AteResult a = io::computeAte(gt, est);
      if (a.trans_m.rmse < 0.1) {
        // Per-frame relative motion error (est pose i-1 -> i vs gt), by timestamp.
        std::map<double, Eigen::Isometry3d> g;
        for (size_t i = 0; i < gt.size(); ++i) g[gt.stamps[i]] = gt.poses[i];
        double sum_t = 0, sum_r = 0;
        for (size_t i = 1; i < est.size(); ++i) {
          const Eigen::Isometry3d de = est.poses[i - 1].inverse() * est.poses[i];
          const Eigen::Isometry3d dg = g.at(est.stamps[i - 1]).inverse() * g.at(est.stamps[i]);
          const Eigen::Isometry3d e = dg.inverse() * de;
          sum_t += e.translation().norm();
          sum_r += Eigen::AngleAxisd(e.rotation()).angle() * 180 / M_PI;
        }
        std::printf("  est %d: mean relative error %.4f m %.3f deg per frame\n", id,
                    sum_t / (est.size() - 1), sum_r / (est.size() - 1));
      }
      std::printf("est %d (%s, %zu poses) vs gt %d: ATE %.4f m\n", id, r.object_class.at(id).c_str(),
                  est.size(), gid, a.trans_m.rmse);
    }
  }
}

}  // namespace
}  // namespace emf::pipeline
