// The dynamic SLAM (EM loop + object lifecycle) on the synthetic `cars` preset: object tracking
// with perfect association (the tracker and object-map accuracy alone), and the whole system fed
// with the simulated detector's detections (camera and per-object ATE against the exact ground
// truth). EMF_OBJECTS_FRAMES overrides the length of the whole-system run (e.g. for a longer
// manual check); the figures of a run are printed.
#include <cstdlib>
#include <limits>
#include <map>
#include <set>

#include "core/frame_source.h"
#include "eval/eval.h"
#include "pipeline/slam_system.h"
#include "sources/open_source.h"
#include "test_support.h"
#include "track/preprocess.h"
#include "track/tracker.h"

namespace emf::pipeline {
namespace {

// Perfect association, noise-free 320x240, 0.7 cm voxels: per-frame error of the camera motion
// relative to the car (measured: 0.52 cm / 0.148 deg mean at the default object truncation of 5
// voxels, 0.69 cm / 0.286 deg at the paper's 10).
constexpr double kPerfectMeanRelativeM = 0.012;
constexpr double kPerfectMeanRelativeDeg = 0.4;
// The default object truncation must beat the paper's on that rotation error by this factor
// (measured 0.52).
constexpr double kTruncationRotationGain = 0.8;
// Whole system, 90 frames of `cars` at 320x240 with the simulated detector every 30 frames.
constexpr double kCameraAteM = 0.01;  // measured 1.8 mm
// Object ATE measured 2.6 / 2.2 cm (3.4 / 4.7 cm with the paper's object truncation and the raw
// depth, when car 2 moved between 4.4 and 5.4 cm with the float summation order of the tracking
// kernel, i.e. its work-group shapes), so the bound leaves room for other CPUs. (Issue target
// 1.5 cm: not met; with perfect association and a ground-truth-posed object map the noise floor
// of this preset is already 1.5 cm at 640x480.)
constexpr double kObjectAteM = 0.06;
constexpr double kObjectCoverage = 0.8;  // fraction of frames an object is tracked

Config smallConfig() {
  Config c;
  c.map.memory_mb = 128;
  c.map.background_voxel_m = 0.02;
  c.map.background_resolution = 256;
  return c;
}

double angleDeg(const Eigen::Isometry3d& T) {
  return Eigen::AngleAxisd(T.rotation()).angle() * 180.0 / M_PI;
}

struct RelativeError {
  double mean_m = 0, mean_deg = 0;
};

// Tracks car 1 of 12 noise-free `cars` frames against its own model, fused at the ground-truth
// camera poses with the exact instance mask as q: the per-frame error of the camera motion
// relative to the car, with the object volume's truncation at `truncation_voxels`.
RelativeError perfectAssociationError(double truncation_voxels) {
  const Config config = smallConfig();
  cl::Context ctx(config.cl);
  auto src = sources::openSource("synth:cars?frames=12&width=320&height=240&seed=1&noise=0",
                                 config.source);
  const core::Intrinsics k = src->intrinsics();
  map::VoxelPool pool(ctx, config.map);
  track::Preprocessor pre(ctx, objectPreprocessOptions(config), k);
  track::Tracker tracker(ctx, objectTrackOptions(config, k.width), k.width, k.height);
  const size_t bytes = sizeof(float) * static_cast<size_t>(k.width * k.height);
  cl::MemHandle q = ctx.buffer(CL_MEM_READ_WRITE, bytes);
  std::unique_ptr<map::Volume> vol;
  const int gid = 1;
  Eigen::Isometry3d T_vc_prev, motion = Eigen::Isometry3d::Identity(), T_oc_gt_prev;
  double sum_m = 0, sum_deg = 0;
  int n = 0;
  core::Frame f;
  while (src->next(f)) {
    cv::Mat mask;
    cv::Mat(f.instance_ids == gid).convertTo(mask, CV_32F, 1.0 / 255);
    ctx.write(q, mask.data, bytes);
    pre.process(f.depth);
    const Eigen::Isometry3d T_oc_gt = f.T_world_object_gt.at(gid).inverse() * *f.T_world_camera_gt;
    Eigen::Isometry3d T_vc;
    if (!vol) {
      // 64^3 voxels of 0.7 cm centred on the object's origin, axes along the world's.
      map::VolumeSpec spec = map::VolumeSpec::object(config.map, 64, 0.007f);
      spec.free_space_full_weight = config.objects.free_space_full_weight;
      spec.truncation_m = static_cast<float>(truncation_voxels * 0.007);
      Eigen::Isometry3d T_wv = Eigen::Isometry3d::Identity();
      T_wv.translation() =
          f.T_world_object_gt.at(gid).translation() - Eigen::Vector3d::Constant(0.224);
      vol = std::make_unique<map::Volume>(pool, spec, T_wv);
      T_vc = T_wv.inverse() * *f.T_world_camera_gt;
    } else {
      const track::TrackResult r =
          tracker.track(deviceView(*vol), pre.vertexMap().get(), q.get(), T_vc_prev * motion);
      EXPECT_FALSE(r.lost) << "frame " << f.index << ": " << r.loss_reason;
      T_vc = r.T_volume_camera;
      motion = T_vc_prev.inverse() * T_vc;
      // Camera motion relative to the car: estimate vs ground truth (frame independent).
      const Eigen::Isometry3d e = (T_oc_gt_prev.inverse() * T_oc_gt).inverse() * motion;
      sum_m += e.translation().norm();
      sum_deg += angleDeg(e);
      ++n;
      vol->setPose(*f.T_world_camera_gt * T_vc.inverse());
    }
    map::IntegrationInput in;
    in.depth = &pre.inputDepth();
    in.weights = &q;
    in.intrinsics = k;
    in.T_world_camera = *f.T_world_camera_gt;
    vol->fuse(in);
    T_vc_prev = T_vc;
    T_oc_gt_prev = T_oc_gt;
  }
  EXPECT_EQ(n, 11);
  RelativeError e;
  if (n > 0) e = {sum_m / n, sum_deg / n};
  std::printf(
      "perfect association, truncation %.0f voxels: mean relative error %.4f m %.3f deg "
      "per frame\n",
      truncation_voxels, e.mean_m, e.mean_deg);
  return e;
}

TEST(SlamObjects, PerfectAssociationTracksTheCar) {
  const RelativeError e = perfectAssociationError(Config{}.objects.truncation_voxels);
  EXPECT_LT(e.mean_m, kPerfectMeanRelativeM);
  EXPECT_LT(e.mean_deg, kPerfectMeanRelativeDeg);
  const RelativeError paper = perfectAssociationError(Config{}.map.truncation_voxels);
  EXPECT_LT(e.mean_deg, kTruncationRotationGain * paper.mean_deg);
}

struct CarsRun {
  double camera_ate_m = 0;
  int created = 0;                        // objects created over the run
  int64_t lost = 0;                       // camera frames lost
  int64_t refused = 0;                    // objects not created for want of pool room
  int64_t pool_full_frames = 0;           // frames the background found no slot for a block
  int64_t map_moves = 0;                  // moves of the background grid (map.follow_camera)
  std::map<int, double> ate_m, coverage;  // per ground-truth car: best estimate (emf eval rule)
};

// `frames` of the cars preset at 320x240 through SlamSystem; detections from the source's
// simulated detector when `source_detections`, otherwise from config.detector's plugin.
CarsRun runCars(const Config& config, int frames, bool source_detections) {
  cl::Context ctx(config.cl);
  const std::string uri =
      "synth:cars?frames=" + std::to_string(frames) + "&width=320&height=240&seed=1";
  auto src = sources::openSource(uri, config.source);
  SlamSystem slam(ctx, config, src->intrinsics(), uri);
  io::Trajectory camera_gt, camera_est;
  std::map<int, io::Trajectory> object_gt, object_est;  // T_object_camera per frame
  core::Frame f;
  CarsRun run;
  std::set<int> seen;  // objects reported so far
  while (src->next(f)) {
    const FrameOutcome o =
        slam.process(f, source_detections && f.detections ? &*f.detections : nullptr);
    camera_gt.append(f.timestamp, *f.T_world_camera_gt);
    camera_est.append(f.timestamp, o.T_world_camera);
    for (const auto& [id, T_wo] : f.T_world_object_gt) {
      object_gt[id].append(f.timestamp, T_wo.inverse() * *f.T_world_camera_gt);
    }
    // Objects confirmed now (objects.confirm_detections): their poses since creation first.
    for (const auto& c : o.confirmed) {
      for (const auto& p : c.earlier) object_est[c.id].append(p.timestamp, p.T_object_camera);
    }
    for (const auto& ob : o.objects) {
      if (seen.insert(ob.id).second) {
        ++run.created;
        // New volumes take the object truncation (objects.truncation_voxels, raised to the
        // pixel floor), not the map's: at 320x240 both cars get fewer than its 10 voxels.
        const map::Volume* volume = slam.volume(ob.id);
        EXPECT_TRUE(volume != nullptr || ob.state == ObjectState::kDeleted) << "object " << ob.id;
        if (volume != nullptr) {
          const double voxels = volume->spec().truncation_m / volume->spec().voxel_size_m;
          EXPECT_GE(voxels, config.objects.truncation_voxels - 1e-4) << "object " << ob.id;
          EXPECT_LT(voxels, config.map.truncation_voxels - 1.0) << "object " << ob.id;
          std::printf("object %d: truncation %.2f voxels of %.2f cm\n", ob.id, voxels,
                      volume->spec().voxel_size_m * 100.0);
        }
      }
      if (ob.state == ObjectState::kTracked && ob.last_frame == o.index) {
        object_est[ob.id].append(f.timestamp, ob.T_object_camera);
      }
    }
  }
  run.camera_ate_m = eval::computeAte(camera_gt, camera_est).trans_m.rmse;
  run.lost = slam.framesLost();
  run.refused = slam.poolRefusedObjects();
  run.pool_full_frames = slam.backgroundPoolFullFrames();
  run.map_moves = slam.backgroundShifts();
  std::printf("camera ATE %.4f m, %lld lost, %d objects created, %lld map moves\n",
              run.camera_ate_m, static_cast<long long>(slam.framesLost()), run.created,
              static_cast<long long>(slam.backgroundShifts()));
  // Each ground-truth car is matched to the estimate with the lowest ATE among those covering
  // enough of its frames (the `emf eval` rule).
  for (const auto& [gid, gt] : object_gt) {
    double best = 1e9, coverage = 0;
    int best_id = 0;
    for (const auto& [id, est] : object_est) {
      const double c = static_cast<double>(est.size()) / static_cast<double>(gt.size());
      if (c < 0.3) continue;
      const double ate = eval::computeAte(gt, est).trans_m.rmse;
      if (ate < best) {
        best = ate;
        best_id = id;
        coverage = c;
      }
    }
    std::printf("car %d: object %d, ATE %.4f m, coverage %.2f\n", gid, best_id, best, coverage);
    run.ate_m[gid] = best;
    run.coverage[gid] = coverage;
  }
  return run;
}

TEST(SlamObjects, CarsPresetWithSimulatedDetections) {
  const char* frames_env = std::getenv("EMF_OBJECTS_FRAMES");
  const int frames = frames_env ? std::atoi(frames_env) : 90;
  const CarsRun run = runCars(smallConfig(), frames, true);
  EXPECT_LT(run.camera_ate_m, kCameraAteM);
  ASSERT_EQ(run.ate_m.size(), 2u);
  for (const auto& [gid, ate] : run.ate_m) {
    EXPECT_LT(ate, kObjectAteM) << "car " << gid;
    EXPECT_GE(run.coverage.at(gid), kObjectCoverage) << "car " << gid;
  }
}

// The cars again while the background grid moves with the camera in one-block steps (8 cm),
// forced although the room fits in it, evicting blocks at its edges: the objects keep their own
// volumes and world poses and track as well as with the map in place (same frames).
constexpr double kMovingMapObjectAteSlackM = 0.005;

TEST(SlamObjects, CarsTrackWhileTheBackgroundMoves) {
  Config config = smallConfig();
  config.map.background_voxel_m = 0.01;  // blocks of 8 cm
  config.map.background_resolution = 512;
  config.map.follow_camera = false;
  const CarsRun fixed = runCars(config, 180, true);
  config.map.follow_camera = true;
  config.map.follow_trigger_m = 0.0;         // one block
  config.map.follow_outside_fraction = 0.0;  // even while the room fits in the grid
  const CarsRun run = runCars(config, 180, true);
  EXPECT_EQ(fixed.map_moves, 0);
  EXPECT_GE(run.map_moves, 5);
  EXPECT_EQ(run.lost, 0);
  EXPECT_LT(run.camera_ate_m, kCameraAteM);
  ASSERT_EQ(run.ate_m.size(), 2u);
  ASSERT_EQ(fixed.ate_m.size(), 2u);
  for (const auto& [gid, ate] : run.ate_m) {
    EXPECT_LT(ate, fixed.ate_m.at(gid) + kMovingMapObjectAteSlackM) << "car " << gid;
    EXPECT_GE(run.coverage.at(gid), kObjectCoverage) << "car " << gid;
  }
}

// The motion plugin alone (no trained detector), every 5th frame with its default thresholds:
// it must find both cars from the SLAM's feedback (residual, background association with
// disocclusions marked explained) and nothing else for long. Measured: 2 objects created, car
// ATE 3.5 / 1.5 cm at coverage 67 / 83 %: the cars are created once seen moving over two calls
// (frames 30 and 15) and tracked to the end. (Before objects.invisible_inside_fraction their
// partial models, 380-400 px in the middle of the image, were deleted as invisible and
// re-created: 3-4 objects.)
constexpr double kMotionObjectAteM = 0.06;
constexpr double kMotionCoverage = 0.6;  // created only once seen moving over two calls
constexpr int kMotionMaxCreated = 4;     // the two cars plus at most two short false regions

TEST(SlamObjects, MotionDetectorFindsBothCars) {
  Config config = smallConfig();
  config.detector.plugin = "motion";
  config.detector.every_n_frames = 5;
  const CarsRun run = runCars(config, 90, false);
  EXPECT_LT(run.camera_ate_m, kCameraAteM);
  EXPECT_LE(run.created, kMotionMaxCreated);
  ASSERT_EQ(run.ate_m.size(), 2u);
  for (const auto& [gid, ate] : run.ate_m) {
    EXPECT_LT(ate, kMotionObjectAteM) << "car " << gid;
    EXPECT_GE(run.coverage.at(gid), kMotionCoverage) << "car " << gid;
  }
}

// A fixed pool of 8 MiB (4096 slots; this background takes ~2200 of them): a car at 256^3
// voxels would need every slot, so it is not created and the camera keeps its map and its
// accuracy (before the rule: 149 of 150 frames lost on `occlusion`). At 4 MiB the background
// itself does not fit: the frames it lost blocks on are counted (run.json, log).
TEST(SlamObjects, AFullPoolRefusesObjectsAndCountsBackgroundDrops) {
  Config config = smallConfig();
  config.map.memory_mb = 8;
  config.objects.resolution = 256;
  const CarsRun big = runCars(config, 30, true);
  EXPECT_EQ(big.created, 0);
  EXPECT_GE(big.refused, 1);
  EXPECT_EQ(big.pool_full_frames, 0);
  EXPECT_EQ(big.lost, 0);
  EXPECT_LT(big.camera_ate_m, kCameraAteM);

  config.objects.resolution = Config{}.objects.resolution;
  config.map.memory_mb = 4;
  const CarsRun small = runCars(config, 30, true);
  EXPECT_GT(small.pool_full_frames, 0);
}

// A frame without depth while the cars are tracked: the camera is lost, and since its E-step
// gave only q_0 (at the camera tracker's pixels) the frame has no associations to show; the
// next frame has them again, q in [0, 1] and summing to at most 1 per pixel.
TEST(SlamObjects, LostCameraFrameShowsNoAssociations) {
  const Config config = smallConfig();
  cl::Context ctx(config.cl);
  const std::string uri = "synth:cars?frames=8&width=320&height=240&seed=1";
  auto src = sources::openSource(uri, config.source);
  SlamSystem slam(ctx, config, src->intrinsics(), uri);
  core::Frame f;
  int frame = 0;
  bool blanked = false, after = false;
  while (src->next(f)) {
    const bool blank = frame == 5;
    if (blank) f.depth.setTo(std::numeric_limits<float>::quiet_NaN());
    const FrameOutcome o = slam.process(f, f.detections ? &*f.detections : nullptr);
    const SlamSystem::Associations a = slam.associations();
    if (blank) {
      blanked = true;
      EXPECT_TRUE(o.lost);
      EXPECT_TRUE(a.ids.empty());
    } else if (frame > 0) {
      ASSERT_FALSE(o.lost) << "frame " << frame << ": " << o.loss_reason;
      ASSERT_GE(a.ids.size(), 2u) << "frame " << frame;  // the background and a car at least
      ASSERT_EQ(a.q.size(), a.ids.size());
      cv::Mat sum = cv::Mat::zeros(a.q[0].size(), CV_32F);
      for (const cv::Mat& q : a.q) {
        double lo = 0, hi = 0;
        cv::minMaxLoc(q, &lo, &hi);
        EXPECT_GE(lo, 0.0);
        EXPECT_LE(hi, 1.0);
        sum += q;
      }
      double most = 0;
      cv::minMaxLoc(sum, nullptr, &most);
      EXPECT_LE(most, 1.0 + 1e-5) << "frame " << frame;
      after = after || blanked;
    }
    ++frame;
  }
  EXPECT_TRUE(blanked);
  EXPECT_TRUE(after);
}

}  // namespace
}  // namespace emf::pipeline
