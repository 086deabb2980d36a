// Ray casting (kernels_cl/raycast.cl) against the CPU reference, against the analytic scene,
// and with several volumes (depth test, p_fg > 0.5 rule, volume ids).
#include "map/raycaster.h"
#include "map_fixture.h"

namespace emf::test {
namespace {

// Kernel and reference march the same float steps; a pixel whose ray grazes a voxel or block
// boundary can still step differently by one rounding, so a small share of pixels may differ
// in hit/no-hit; where both hit, depths agree closely.
constexpr float kRaycastDepthToleranceM = 1e-4f;
constexpr float kNormalDotTolerance = 1e-3f;       // 1 - n_dev . n_ref
constexpr double kMaxHitMismatchFraction = 0.002;  // of all pixels

struct Compare {
  int both = 0, mismatch = 0, id_mismatch = 0, depth_bad = 0, normal_bad = 0;
};

Compare compareImages(const cv::Mat& depth, const cv::Mat& normals, const cv::Mat& ids,
                      const map::RaycastImages& ref) {
  Compare c;
  for (int y = 0; y < depth.rows; ++y) {
    for (int x = 0; x < depth.cols; ++x) {
      const float a = depth.at<float>(y, x), b = ref.depth.at<float>(y, x);
      if (std::isnan(a) != std::isnan(b)) {
        ++c.mismatch;
        continue;
      }
      if (std::isnan(a)) continue;
      ++c.both;
      c.id_mismatch += ids.at<int>(y, x) != ref.ids.at<int>(y, x);
      c.depth_bad += std::abs(a - b) > kRaycastDepthToleranceM;
      const cv::Vec3f na = normals.at<cv::Vec3f>(y, x), nb = ref.normals.at<cv::Vec3f>(y, x);
      c.normal_bad += 1.f - na.dot(nb) > kNormalDotTolerance;
    }
  }
  return c;
}

class Raycast : public MapTest {};

TEST_F(Raycast, BackgroundMatchesReferenceAndTheScene) {
  const map::MapOptions o = smallOptions();
  map::VoxelPool pool(ctx(), o);
  const map::VolumeSpec spec = map::VolumeSpec::background(o);
  const Eigen::Isometry3d T0 = Eigen::Isometry3d::Identity();
  map::Volume vol(pool, spec, map::backgroundVolumePose(o, spec, T0));
  const core::Intrinsics k = testIntrinsics(320, 240);
  const Scene scene;
  const Eigen::Isometry3d T1 = lookAt(Eigen::Vector3d(0.3, -0.1, 0.2), Eigen::Vector3d(0, 0.3, 2));
  for (const auto& T : {T0, T1}) {
    Frame f = makeFrame(renderDepth(scene, k, T), k, T);
    vol.fuse(f.input);
  }
  map::RayCaster caster(ctx(), o, 640, 480);
  const Eigen::Isometry3d Tv = lookAt(Eigen::Vector3d(0.1, -0.05, 0.1), Eigen::Vector3d(0, 0.2, 2));
  caster.render({{&vol, 7}}, k, Tv);
  cv::Mat depth, normals, ids;
  caster.download(&depth, &normals, &ids);
  const map::VolumeHostData h = vol.download();
  // raycast_bounds: the per-tile depth ranges equal the reference exactly.
  std::vector<float> z_min, z_max;
  caster.downloadTileRanges(&z_min, &z_max);
  const map::TileRanges ranges = map::tileRangesReference(
      h, cameraF(k), map::PoseRows::from(Tv.inverse() * vol.T_world_volume()), o);
  ASSERT_EQ(z_min.size(), ranges.z_min.size());
  int covered = 0;
  for (size_t i = 0; i < z_min.size(); ++i) {
    ASSERT_EQ(z_min[i], ranges.z_min[i]) << "tile " << i;
    ASSERT_EQ(z_max[i], ranges.z_max[i]) << "tile " << i;
    covered += std::isfinite(z_min[i]);
  }
  EXPECT_GT(covered, static_cast<int>(z_min.size()) / 2);
  const map::RaycastImages ref = map::raycastReference({{&h, 7}}, cameraF(k), Tv, o);
  const Compare c = compareImages(depth, normals, ids, ref);
  const int n = k.width * k.height;
  EXPECT_GT(c.both, n / 2);
  EXPECT_LE(c.mismatch, kMaxHitMismatchFraction * n);
  EXPECT_EQ(c.id_mismatch, 0);
  EXPECT_LE(c.depth_bad, kMaxHitMismatchFraction * n);
  EXPECT_LE(c.normal_bad, kMaxHitMismatchFraction * n);
  // Against the analytic depth from the new pose: half a voxel median, nearly all within 1.5.
  const cv::Mat truth = renderDepth(scene, k, Tv);
  std::vector<float> err;
  for (int y = 0; y < k.height; ++y) {
    for (int x = 0; x < k.width; ++x) {
      const float a = depth.at<float>(y, x), t = truth.at<float>(y, x);
      if (!std::isnan(a) && !std::isnan(t)) err.push_back(std::abs(a - t));
      if (!std::isnan(a)) {
        EXPECT_EQ(ids.at<int>(y, x), 7);
      }
    }
  }
  ASSERT_GT(err.size(), static_cast<size_t>(n / 2));
  std::sort(err.begin(), err.end());
  EXPECT_LT(err[err.size() / 2], 0.5f * spec.voxel_size_m);
  EXPECT_LT(err[err.size() * 95 / 100], 1.5f * spec.voxel_size_m);
  // Normals face the camera (up to grazing views of the floor, where the trilinear gradient
  // of a 2 cm grid is ambiguous): clearly back-facing normals are rare.
  int facing = 0, back_facing = 0, normals_n = 0;
  for (int y = 0; y < k.height; ++y) {
    for (int x = 0; x < k.width; ++x) {
      if (std::isnan(depth.at<float>(y, x))) continue;
      const cv::Vec3f nn = normals.at<cv::Vec3f>(y, x);
      const Eigen::Vector3f ray((x - k.cx) / k.fx, (y - k.cy) / k.fy, 1.0);
      ++normals_n;
      const float cos_view = Eigen::Vector3f(nn[0], nn[1], nn[2]).dot(ray.normalized());
      facing += cos_view < 0.f;
      back_facing += cos_view > 0.3f;
      EXPECT_NEAR(cv::norm(nn), 1.0, 1e-4);
    }
  }
  EXPECT_GT(facing, 0.97 * normals_n);
  EXPECT_LT(back_facing, 0.001 * normals_n);
}

TEST_F(Raycast, SeveralVolumesDepthTestAndForegroundRule) {
  const map::MapOptions o = smallOptions();
  map::VoxelPool pool(ctx(), o);
  const Scene scene;
  const map::VolumeSpec bspec = map::VolumeSpec::background(o);
  const Eigen::Isometry3d T0 = Eigen::Isometry3d::Identity();
  map::Volume bg(pool, bspec, map::backgroundVolumePose(o, bspec, T0));
  // Two object volumes: a box around sphere 0 (its mask says foreground) and one around
  // sphere 1 whose mask says background everywhere (never rendered).
  std::vector<std::unique_ptr<map::Volume>> objects;
  for (int i = 0; i < 2; ++i) {
    Eigen::Isometry3d T_wv = Eigen::Isometry3d::Identity();
    T_wv.translation() =
        scene.spheres[static_cast<size_t>(i)].centre_w - Eigen::Vector3d::Constant(0.48);
    objects.push_back(
        std::make_unique<map::Volume>(pool, map::VolumeSpec::object(o, 64, 0.015f), T_wv));
  }
  const core::Intrinsics k = testIntrinsics(320, 240);
  const cv::Mat depth0 = renderDepth(scene, k, T0);
  const cv::Mat s0 = renderSpheres(scene, {0}, k, T0);
  cv::Mat mask0(k.height, k.width, CV_32FC1), mask1(k.height, k.width, CV_32FC1, cv::Scalar(0));
  for (int y = 0; y < k.height; ++y) {
    for (int x = 0; x < k.width; ++x) {
      const float a = s0.at<float>(y, x);
      mask0.at<float>(y, x) =
          !std::isnan(a) && std::abs(a - depth0.at<float>(y, x)) < 1e-4f ? 1.f : 0.f;
    }
  }
  Frame fb = makeFrame(depth0, k, T0);
  Frame f0 = makeFrame(depth0, k, T0, cv::Mat(), mask0);
  Frame f1 = makeFrame(depth0, k, T0, cv::Mat(), mask1);
  bg.fuse(fb.input);
  objects[0]->fuse(f0.input);
  objects[1]->fuse(f1.input);

  map::RayCaster caster(ctx(), o, 320, 240);
  const Eigen::Isometry3d Tv =
      lookAt(Eigen::Vector3d(0.05, 0.0, 0.05), Eigen::Vector3d(0, 0.25, 2));
  constexpr float kMargin = 0.02f;  // one background voxel
  const std::vector<map::RenderItem> items = {
      {&bg, 0, 0.f}, {objects[0].get(), 1, kMargin}, {objects[1].get(), 2, kMargin}};
  caster.render(items, k, Tv);
  cv::Mat depth, normals, ids;
  caster.download(&depth, &normals, &ids);
  const map::VolumeHostData hb = bg.download(), h0 = objects[0]->download(),
                            h1 = objects[1]->download();
  const map::RaycastImages ref = map::raycastReference(
      {{&hb, 0, 0.f}, {&h0, 1, kMargin}, {&h1, 2, kMargin}}, cameraF(k), Tv, o);
  const Compare c = compareImages(depth, normals, ids, ref);
  const int n = k.width * k.height;
  EXPECT_LE(c.mismatch, kMaxHitMismatchFraction * n);
  EXPECT_LE(c.id_mismatch, kMaxHitMismatchFraction * n);
  EXPECT_LE(c.depth_bad, kMaxHitMismatchFraction * n);

  // Object 1 pixels: the sphere 0 silhouette seen from Tv (where it is the nearest surface);
  // object 2 (p_fg = 0) never appears; the background fills the rest.
  const cv::Mat truth_all = renderDepth(scene, k, Tv);
  const cv::Mat truth_s0 = renderSpheres(scene, {0}, k, Tv);
  int on_sphere = 0, on_sphere_obj = 0, off_sphere = 0, off_sphere_bg = 0;
  for (int y = 2; y < k.height - 2; ++y) {
    for (int x = 2; x < k.width - 2; ++x) {
      const int id = ids.at<int>(y, x);
      ASSERT_NE(id, 2) << "an object with p_fg = 0 must not render";
      const float t = truth_s0.at<float>(y, x);
      const bool sphere_front = !std::isnan(t) && std::abs(t - truth_all.at<float>(y, x)) < 1e-4f;
      // Interior pixels only (2 px away from the silhouette in every direction).
      bool interior = sphere_front;
      bool exterior = !sphere_front;
      for (int dy = -2; dy <= 2; ++dy) {
        for (int dx = -2; dx <= 2; ++dx) {
          const float tt = truth_s0.at<float>(y + dy, x + dx);
          const bool f =
              !std::isnan(tt) && std::abs(tt - truth_all.at<float>(y + dy, x + dx)) < 1e-4f;
          interior &= f;
          exterior &= !f;
        }
      }
      if (std::isnan(depth.at<float>(y, x))) continue;
      if (interior) {
        ++on_sphere;
        on_sphere_obj += id == 1;
      } else if (exterior) {
        ++off_sphere;
        off_sphere_bg += id == 0;
      }
    }
  }
  EXPECT_GT(on_sphere, 1000);
  EXPECT_GT(on_sphere_obj, 0.85 * on_sphere) << on_sphere_obj << " of " << on_sphere;
  EXPECT_GT(off_sphere_bg, 0.99 * off_sphere) << off_sphere_bg << " of " << off_sphere;
}

}  // namespace
}  // namespace emf::test
