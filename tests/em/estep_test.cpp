// The E-step kernel (kernels_cl/estep.cl) against its CPU reference on PoCL, and the
// association it produces on a constructed scene: a room corner (background volume, walls only)
// and two boxes, each in its own object volume with foreground/background counts.
#include "em/estep.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "map/map_math.h"
#include "test_support.h"
#include "track/tracker.h"
#include "track_test_support.h"

namespace emf::em {
namespace {

constexpr float kQTolerance = 1e-4f;         // |q kernel - q reference| (float exp, sums)
constexpr float kResidualTolerance = 1e-5f;  // |residual kernel - reference|, metres
constexpr float kFgCounts = 0.95f;           // p_fg written into voxels near the box
constexpr float kBgCounts = 0.05f;           // elsewhere in the object volume

// An object volume holding one box, with a count block per TSDF block.
struct ObjectVolume {
  test::HostVolume tsdf;
  std::vector<int32_t> count_index;
  Eigen::Isometry3d T_background_object = Eigen::Isometry3d::Identity();
  int blocks_without_counts = 0;
  int saturated_voxels = 0;  // count halves above 32767
  ObjectVolume() : tsdf({1, 1, 1}, 0.01f, 0.1f) {}
  map::VolumeHostView view() const {
    map::VolumeHostView v = tsdf.view();
    v.count_index = count_index.data();
    return v;
  }
};

ObjectVolume makeObject(const test::AnalyticScene::Box& box) {
  ObjectVolume o;
  const float voxel = 0.01f, extent = 0.8f;
  const int blocks = static_cast<int>(std::ceil(extent / voxel / map::kBlockSize));
  const Eigen::Vector3f corner = box.center - Eigen::Vector3f::Constant(extent / 2);
  o.T_background_object.translation() = corner.cast<double>();
  test::AnalyticScene only_box;
  only_box.boxes.push_back({box.center - corner, box.half_extent});
  o.tsdf = test::volumeFromSdf([&](const Eigen::Vector3f& x) { return only_box.sdf(x); },
                               Eigen::Vector3i::Constant(blocks), voxel, 0.1f, 10.0f);
  // Count blocks: one per allocated TSDF block except every 5th (its voxels count zero),
  // appended to the same voxel array.
  o.count_index.assign(o.tsdf.index.size(), -1);
  const int tsdf_slots = o.tsdf.allocatedBlocks();
  int next = tsdf_slots;
  int allocated = 0;
  for (size_t b = 0; b < o.tsdf.index.size(); ++b) {
    if (o.tsdf.index[b] < 0) continue;
    const Eigen::Vector3f centre =
        (map::blockCoords(o.tsdf.dims_blocks, static_cast<int>(b)).cast<float>() +
         Eigen::Vector3f::Constant(0.5f)) *
        (voxel * map::kBlockSize);
    const bool near_box =
        ((centre - (box.center - corner)).cwiseAbs() - box.half_extent).maxCoeff() < 0.15f;
    if (!near_box && allocated++ % 5 == 4) {
      ++o.blocks_without_counts;
      continue;
    }
    o.count_index[b] = next++;
  }
  o.tsdf.voxels.resize(static_cast<size_t>(next) * map::kBlockVoxels);
  const Eigen::Vector3i dims = o.tsdf.dims_blocks;
  for (size_t b = 0; b < o.count_index.size(); ++b) {
    if (o.count_index[b] < 0) continue;
    const Eigen::Vector3i bc = map::blockCoords(dims, static_cast<int>(b));
    for (int l = 0; l < map::kBlockVoxels; ++l) {
      const Eigen::Vector3i lv(l % map::kBlockSize, (l / map::kBlockSize) % map::kBlockSize,
                               l / (map::kBlockSize * map::kBlockSize));
      const Eigen::Vector3f c = map::voxelCentre(bc * map::kBlockSize + lv, voxel);
      const bool near_box =
          ((c - (box.center - corner)).cwiseAbs() - box.half_extent).maxCoeff() < 0.05f;
      map::Voxel& v = o.tsdf.voxels[static_cast<size_t>(o.count_index[b]) * map::kBlockVoxels +
                                    static_cast<size_t>(l)];
      // Counts vary from voxel to voxel (a kernel reading a neighbour's counts differs from
      // the reference), and every 7th voxel has seen so many observations that its halves
      // exceed 32767 (read as unsigned).
      const Eigen::Vector3i g = bc * map::kBlockSize + lv;
      const float wobble =
          0.1f * static_cast<float>((g.x() * 7 + g.y() * 13 + g.z() * 29) % 10) / 9;
      const int observations = (g.x() + g.y() + g.z()) % 7 == 0 ? 300 : 4;
      for (int k = 0; k < observations; ++k) {
        v = map::addCounts(v, near_box ? kFgCounts - wobble : kBgCounts + wobble);
      }
      const Eigen::Vector2f raw_counts = map::counts(v) * map::kCountScale;
      o.saturated_voxels += raw_counts.maxCoeff() > 32767.0f;
    }
  }
  return o;
}

cv::Mat backProject(const cv::Mat& depth, const core::Intrinsics& k) {
  cv::Mat vertex(depth.size(), CV_32FC4, cv::Scalar(0, 0, 0, 0));
  for (int v = 0; v < depth.rows; ++v) {
    for (int u = 0; u < depth.cols; ++u) {
      const float z = depth.at<float>(v, u);
      if (std::isnan(z)) continue;
      vertex.at<cv::Vec4f>(v, u) = cv::Vec4f(static_cast<float>((u - k.cx) / k.fx) * z,
                                             static_cast<float>((v - k.cy) / k.fy) * z, z, 1.0f);
    }
  }
  return vertex;
}

// The bounding rectangle of the pixels with q > 0 (empty: none).
cv::Rect positiveBounds(const cv::Mat& q) {
  int x0 = q.cols, y0 = q.rows, x1 = -1, y1 = -1;
  for (int v = 0; v < q.rows; ++v) {
    for (int u = 0; u < q.cols; ++u) {
      if (!(q.at<float>(v, u) > 0.0f)) continue;
      x0 = std::min(x0, u);
      y0 = std::min(y0, v);
      x1 = std::max(x1, u);
      y1 = std::max(y1, v);
    }
  }
  return x1 < 0 ? cv::Rect() : cv::Rect(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
}

class EStepModes : public test::WithClContext, public ::testing::WithParamInterface<const char*> {};

TEST_P(EStepModes, KernelMatchesReferenceAndSeparatesObjectsFromBackground) {
  const test::AnalyticScene scene = test::roomCornerScene();
  test::AnalyticScene walls = scene;
  walls.boxes.clear();
  const float bg_voxel = 0.02f;
  const test::HostVolume background =
      test::volumeFromSdf([&](const Eigen::Vector3f& x) { return walls.sdf(x); },
                          Eigen::Vector3i::Constant(16), bg_voxel, 10 * bg_voxel, 10.0f);
  const ObjectVolume obj1 = makeObject(scene.boxes[0]);
  const ObjectVolume obj2 = makeObject(scene.boxes[1]);
  EXPECT_GT(obj1.blocks_without_counts + obj2.blocks_without_counts, 0);
  EXPECT_GT(obj1.saturated_voxels + obj2.saturated_voxels, 1000);

  // 161 pixels per row: the last group of 16 pixels is partial; a run of invalid vertices on
  // row 10 makes whole groups that no volume contains.
  core::Intrinsics k = test::smallCamera().scaled(161, 120);
  const Eigen::Isometry3d T_bg_camera = test::roomCornerCamera();
  const cv::Mat depth = scene.render(k, T_bg_camera);
  const cv::Mat wall_depth = walls.render(k, T_bg_camera);
  cv::Mat vertex = backProject(depth, k);
  for (int u = 20; u < 60; ++u) vertex.at<cv::Vec4f>(10, u) = cv::Vec4f(0, 0, 0, 0);

  EmOptions options;
  options.association = std::string(GetParam()) == "em" ? Association::kEm : Association::kPfg;
  const bool em_mode = options.association == Association::kEm;
  std::vector<EStepHostVolume> host = {
      {background.view(), T_bg_camera, {}},
      {obj1.view(), obj1.T_background_object.inverse() * T_bg_camera, {}},
      {obj2.view(), obj2.T_background_object.inverse() * T_bg_camera, {}}};
  cv::Mat residual_ref;
  const std::vector<cv::Mat> q_ref = eStepReference(host, vertex, options, &residual_ref);

  // Device: every volume has its own voxel buffer here (the pool is shared in the system).
  const test::DeviceVolume d_bg = test::upload(ctx(), background);
  const test::DeviceVolume d_1 = test::upload(ctx(), obj1.tsdf);
  const test::DeviceVolume d_2 = test::upload(ctx(), obj2.tsdf);
  const cl::MemHandle c_1 =
      ctx().buffer(CL_MEM_READ_ONLY, obj1.count_index.size() * 4, obj1.count_index.data());
  const cl::MemHandle c_2 =
      ctx().buffer(CL_MEM_READ_ONLY, obj2.count_index.size() * 4, obj2.count_index.data());
  const cl::MemHandle d_vertex =
      ctx().buffer(CL_MEM_READ_ONLY, vertex.total() * sizeof(cv::Vec4f), vertex.data);
  EStep estep(ctx(), options, k.width, k.height, 4);
  // The background twice: the second volume without counts takes the accumulating branch of the
  // 16-lane likelihood kernel (the first one initialises sum, best and residual).
  {
    const std::vector<cv::Mat> q_twice_ref = eStepReference({host[0], host[0]}, vertex, options);
    const EStepVolume bg{d_bg.view, nullptr, host[0].T_volume_camera, {}, {}};
    estep.compute(d_vertex.get(), {bg, bg});
    for (int i = 0; i < 2; ++i) {
      EXPECT_LT(cv::norm(estep.downloadQ(i), q_twice_ref[static_cast<size_t>(i)], cv::NORM_INF),
                kQTolerance)
          << "volume " << i;
    }
  }
  estep.compute(d_vertex.get(), {{d_bg.view, nullptr, host[0].T_volume_camera, {}, {}},
                                 {d_1.view, c_1.get(), host[1].T_volume_camera, {}, {}},
                                 {d_2.view, c_2.get(), host[2].T_volume_camera, {}, {}}});
  ctx().finish();
  ASSERT_EQ(estep.volumeCount(), 3);
  // Each object's claimed pixels: the bounding rectangle of its q > 0, kept on the device.
  for (int i = 1; i < 3; ++i) {
    const cv::Rect expected = positiveBounds(estep.downloadQ(i));
    EXPECT_GT(expected.area(), 400) << "volume " << i;
    EXPECT_EQ(estep.claimedPixels(i), expected) << "volume " << i;
  }
  EXPECT_THROW(estep.claimedPixels(0), InvalidArgument);
  EXPECT_THROW(estep.claimedPixels(3), InvalidArgument);

  for (int i = 0; i < 3; ++i) {
    const cv::Mat q = estep.downloadQ(i);
    double max_diff = 0;
    for (int v = 0; v < q.rows; ++v) {
      for (int u = 0; u < q.cols; ++u) {
        max_diff = std::max(max_diff, std::fabs(static_cast<double>(q.at<float>(v, u)) -
                                                q_ref[static_cast<size_t>(i)].at<float>(v, u)));
      }
    }
    EXPECT_LT(max_diff, kQTolerance) << "volume " << i;
  }
  const cv::Mat residual = estep.downloadResidual();
  int residual_mismatch = 0;
  for (int v = 0; v < residual.rows; ++v) {
    for (int u = 0; u < residual.cols; ++u) {
      const float a = residual.at<float>(v, u), b = residual_ref.at<float>(v, u);
      if (std::isnan(a) != std::isnan(b) ||
          (!std::isnan(a) && std::fabs(a - b) > kResidualTolerance)) {
        ++residual_mismatch;
      }
    }
  }
  EXPECT_EQ(residual_mismatch, 0);

  // Semantics: box pixels belong to their object, wall pixels to the background, q sums to 1
  // (in the ablation mode too: p_fg near the boxes is 0.95, elsewhere 0.05).
  const cv::Mat q0 = estep.downloadQ(0), q1 = estep.downloadQ(1), q2 = estep.downloadQ(2);
  int box_px = 0, box_ok = 0, wall_px = 0, wall_ok = 0, sum_bad = 0;
  for (int v = 0; v < depth.rows; ++v) {
    for (int u = 0; u < depth.cols; ++u) {
      const float z = depth.at<float>(v, u), zw = wall_depth.at<float>(v, u);
      if (std::isnan(z) || vertex.at<cv::Vec4f>(v, u)[3] == 0.0f) continue;
      const float s = q0.at<float>(v, u) + q1.at<float>(v, u) + q2.at<float>(v, u);
      if (std::fabs(s - 1.0f) > (em_mode ? 1e-5f : 0.06f)) ++sum_bad;
      const Eigen::Vector3d p = T_bg_camera * Eigen::Vector3d(vertex.at<cv::Vec4f>(v, u)[0],
                                                              vertex.at<cv::Vec4f>(v, u)[1], z);
      const auto inside = [&](const test::AnalyticScene::Box& b) {
        return ((p.cast<float>() - b.center).cwiseAbs() - b.half_extent).maxCoeff() < 0.005f;
      };
      if (inside(scene.boxes[0])) {
        ++box_px;
        if (q1.at<float>(v, u) > 0.8f) ++box_ok;
      } else if (inside(scene.boxes[1])) {
        ++box_px;
        if (q2.at<float>(v, u) > 0.8f) ++box_ok;
      } else if (std::fabs(z - zw) < 1e-4f) {
        ++wall_px;
        if (q0.at<float>(v, u) > 0.8f) ++wall_ok;
      }
    }
  }
  EXPECT_EQ(sum_bad, 0);
  ASSERT_GT(box_px, 200);
  ASSERT_GT(wall_px, 2000);
  EXPECT_GT(box_ok, 0.9 * box_px) << box_ok << " of " << box_px;
  EXPECT_GT(wall_ok, 0.9 * wall_px) << wall_ok << " of " << wall_px;

  // Object 1 claims only the half of its grid with x below the middle (objects.claim_region):
  // beyond it, it gets q_1 = 0 as outside its grid, and the kernel still matches the reference.
  const map::VolumeHostView v1 = obj1.view();
  ClaimBox half;
  half.hi.x() = 0.5f * static_cast<float>(v1.dims_blocks.x() * map::kBlockSize) * v1.voxel_size_m;
  std::vector<EStepHostVolume> host_half = host;
  host_half[1].claim = half;
  const std::vector<cv::Mat> q_half_ref = eStepReference(host_half, vertex, options);
  estep.compute(d_vertex.get(), {{d_bg.view, nullptr, host[0].T_volume_camera, {}, {}},
                                 {d_1.view, c_1.get(), host[1].T_volume_camera, half, {}},
                                 {d_2.view, c_2.get(), host[2].T_volume_camera, {}, {}}});
  for (int i = 0; i < 3; ++i) {
    EXPECT_LT(cv::norm(estep.downloadQ(i), q_half_ref[static_cast<size_t>(i)], cv::NORM_INF),
              kQTolerance)
        << "volume " << i << " with object 1 claiming half its grid";
  }
  const cv::Mat q1_half = estep.downloadQ(1);
  int cut = 0, cut_nonzero = 0, kept = 0;
  for (int v = 0; v < vertex.rows; ++v) {
    for (int u = 0; u < vertex.cols; ++u) {
      const cv::Vec4f p = vertex.at<cv::Vec4f>(v, u);
      if (p[3] == 0.0f) continue;
      const Eigen::Vector3f in_1 =
          (host[1].T_volume_camera * Eigen::Vector3d(p[0], p[1], p[2])).cast<float>();
      if (q1.at<float>(v, u) < 0.5f) continue;  // object 1's own pixels without the box
      if (in_1.x() >= half.hi.x()) {
        ++cut;
        if (q1_half.at<float>(v, u) != 0.0f) ++cut_nonzero;
      } else if (q1_half.at<float>(v, u) >= 0.5f) {
        ++kept;
      }
    }
  }
  EXPECT_GT(cut, 50);
  EXPECT_EQ(cut_nonzero, 0);
  EXPECT_GT(kept, 50);

  // Each object evaluated only over the pixels its grid projects to (track::volumeImageBounds):
  // q and the residual are those of the whole image, to the bit.
  const auto gridPixels = [&](const map::VolumeHostView& view, const Eigen::Isometry3d& T) {
    return track::volumeImageBounds(
               view.dims_blocks.cast<double>() * map::kBlockSize * view.voxel_size_m, T, k)
        .toCv();
  };
  const cv::Rect px_1 = gridPixels(obj1.view(), host[1].T_volume_camera);
  const cv::Rect px_2 = gridPixels(obj2.view(), host[2].T_volume_camera);
  ASSERT_LT(px_1.area() + px_2.area(), k.width * k.height);  // the rectangles do cut work
  estep.compute(d_vertex.get(), {{d_bg.view, nullptr, host[0].T_volume_camera, {}, {}},
                                 {d_1.view, c_1.get(), host[1].T_volume_camera, {}, {}},
                                 {d_2.view, c_2.get(), host[2].T_volume_camera, {}, {}}});
  std::vector<cv::Mat> q_whole;
  for (int i = 0; i < 3; ++i) q_whole.push_back(estep.downloadQ(i));
  const cv::Mat residual_whole = estep.downloadResidual();
  estep.compute(d_vertex.get(), {{d_bg.view, nullptr, host[0].T_volume_camera, {}, {}},
                                 {d_1.view, c_1.get(), host[1].T_volume_camera, {}, px_1},
                                 {d_2.view, c_2.get(), host[2].T_volume_camera, {}, px_2}});
  const auto sameBits = [](const cv::Mat& a, const cv::Mat& b) {
    return a.size() == b.size() && a.type() == b.type() &&
           std::memcmp(a.data, b.data, a.total() * a.elemSize()) == 0;
  };
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(sameBits(estep.downloadQ(i), q_whole[static_cast<size_t>(i)])) << "volume " << i;
  }
  EXPECT_TRUE(sameBits(estep.downloadResidual(), residual_whole));
  // Without the residual everywhere the background's SDF is sampled only where an object's
  // rectangle reaches: the same q, the same residual there, NaN elsewhere.
  estep.compute(d_vertex.get(),
                {{d_bg.view, nullptr, host[0].T_volume_camera, {}, {}},
                 {d_1.view, c_1.get(), host[1].T_volume_camera, {}, px_1},
                 {d_2.view, c_2.get(), host[2].T_volume_camera, {}, px_2}},
                false);
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(sameBits(estep.downloadQ(i), q_whole[static_cast<size_t>(i)])) << "volume " << i;
  }
  {
    const cv::Mat residual_objects = estep.downloadResidual();
    int inside_same = 0, inside_other = 0, outside_nan = 0, outside_set = 0;
    for (int v = 0; v < k.height; ++v) {
      for (int u = 0; u < k.width; ++u) {
        const float a = residual_objects.at<float>(v, u), b = residual_whole.at<float>(v, u);
        // The background pass decides per 16 pixels of a row (EMF_ESTEP_EXACT_COLS): a group
        // touching a rectangle is exact.
        const int g0 = u / 16 * 16;
        const cv::Rect group(g0, v, 16, 1);
        if ((group & px_1).area() > 0 || (group & px_2).area() > 0) {
          (std::memcmp(&a, &b, sizeof(float)) == 0 ? inside_same : inside_other)++;
        } else if (!std::isnan(b)) {
          (std::isnan(a) ? outside_nan : outside_set)++;
        }
      }
    }
    EXPECT_GT(inside_same, 0);
    EXPECT_EQ(inside_other, 0);
    EXPECT_GT(outside_nan, 1000);  // valid background pixels whose SDF was not sampled
    EXPECT_EQ(outside_set, 0);
  }
  // More objects than the background pass takes rectangles (8): object 1 ten times, each copy
  // seeing one strip of its rectangle; the rectangles are merged, q_0 is still exact.
  {
    EStep many(ctx(), options, k.width, k.height, 11);
    std::vector<EStepVolume> strips = {{d_bg.view, nullptr, host[0].T_volume_camera, {}, {}}};
    for (int j = 0; j < 10; ++j) {
      const int x0 = px_1.x + px_1.width * j / 10, x1 = px_1.x + px_1.width * (j + 1) / 10;
      strips.push_back({d_1.view,
                        c_1.get(),
                        host[1].T_volume_camera,
                        {},
                        cv::Rect(x0, px_1.y, x1 - x0, px_1.height)});
    }
    many.compute(d_vertex.get(), strips, false);
    estep.compute(d_vertex.get(), {{d_bg.view, nullptr, host[0].T_volume_camera, {}, {}},
                                   {d_1.view, c_1.get(), host[1].T_volume_camera, {}, px_1}});
    EXPECT_TRUE(sameBits(many.downloadQ(0), estep.downloadQ(0)));
  }
  // The frame's second E-step: the background moved, the objects did not. Their likelihoods
  // are reused, with the same q as sampling them again; an object that moved is sampled again.
  {
    Eigen::Isometry3d T_bg_moved = host[0].T_volume_camera;
    T_bg_moved.translate(Eigen::Vector3d(0.004, -0.002, 0.003));
    const std::vector<EStepVolume> first = {
        {d_bg.view, nullptr, host[0].T_volume_camera, {}, {}},
        {d_1.view, c_1.get(), host[1].T_volume_camera, {}, px_1},
        {d_2.view, c_2.get(), host[2].T_volume_camera, {}, px_2}};
    std::vector<EStepVolume> second = first;
    second[0].T_volume_camera = T_bg_moved;
    estep.compute(d_vertex.get(), second, false, false);
    std::vector<cv::Mat> q_sampled;
    for (int i = 0; i < 3; ++i) q_sampled.push_back(estep.downloadQ(i));
    const int sampled_residuals =
        cv::countNonZero(estep.downloadResidual() == estep.downloadResidual());
    EXPECT_FALSE(estep.reusedObjects());
    estep.compute(d_vertex.get(), first, false, false);
    estep.compute(d_vertex.get(), second, false, true);
    EXPECT_TRUE(estep.reusedObjects());
    // Reused, the background's SDF is sampled only where the objects claim pixels (the residual,
    // NaN where it was not sampled, shows where): fewer pixels than over their rectangles.
    const int reused_residuals =
        cv::countNonZero(estep.downloadResidual() == estep.downloadResidual());
    EXPECT_LT(reused_residuals, sampled_residuals);
    EXPECT_GT(reused_residuals, 0);
    for (int i = 0; i < 3; ++i) {
      EXPECT_TRUE(sameBits(estep.downloadQ(i), q_sampled[static_cast<size_t>(i)]))
          << "volume " << i << " with the objects' likelihoods reused";
      if (i > 0) {
        EXPECT_EQ(estep.claimedPixels(i), positiveBounds(q_sampled[static_cast<size_t>(i)]))
            << "volume " << i;
      }
    }
    if (em_mode) {
      EXPECT_FALSE(sameBits(estep.downloadQ(0), q_whole[0]));  // the background did move
    }
    // Object 2 moved too: nothing is reused, q is that of its new pose.
    std::vector<EStepVolume> third = second;
    third[2].T_volume_camera.translate(Eigen::Vector3d(0.01, 0.0, 0.0));
    estep.compute(d_vertex.get(), third, false, false);
    const cv::Mat q2_moved = estep.downloadQ(2);
    estep.compute(d_vertex.get(), first, false, false);
    estep.compute(d_vertex.get(), third, false, true);
    EXPECT_FALSE(estep.reusedObjects());
    EXPECT_TRUE(sameBits(estep.downloadQ(2), q2_moved));
  }
  // The camera's E-step: the background's weights alone at every pixel / 2nd / 3rd pixel equal
  // the whole E-step's q_0 there to the bit; the objects' q are untouched, and the next
  // compute() reuses the objects' likelihoods, with the same q as sampling them.
  {
    const std::vector<EStepVolume> volumes = {
        {d_bg.view, nullptr, host[0].T_volume_camera, {}, {}},
        {d_1.view, c_1.get(), host[1].T_volume_camera, {}, px_1},
        {d_2.view, c_2.get(), host[2].T_volume_camera, {}, px_2}};
    estep.compute(d_vertex.get(), volumes, false, false);
    std::vector<cv::Mat> q_full;
    for (int i = 0; i < 3; ++i) q_full.push_back(estep.downloadQ(i));
    for (int stride : {1, 2, 3}) {
      SCOPED_TRACE("stride " + std::to_string(stride));
      estep.computeBackgroundWeights(d_vertex.get(), volumes, stride);
      const cv::Mat q0_strided = estep.downloadQ(0);
      int same = 0, other = 0;
      for (int v = 0; v < k.height; v += stride) {
        for (int u = 0; u < k.width; u += stride) {
          const float a = q0_strided.at<float>(v, u), b = q_full[0].at<float>(v, u);
          (std::memcmp(&a, &b, sizeof(float)) == 0 ? same : other)++;
        }
      }
      EXPECT_EQ(other, 0);
      EXPECT_EQ(same, ((k.width + stride - 1) / stride) * ((k.height + stride - 1) / stride));
      EXPECT_TRUE(sameBits(estep.downloadQ(1), q_full[1]));
      EXPECT_TRUE(sameBits(estep.downloadQ(2), q_full[2]));
      // Only the background's q is new: claimedPixels has no object q to bound.
      EXPECT_THROW(estep.claimedPixels(1), InvalidArgument);
      estep.compute(d_vertex.get(), volumes, false, true);
      EXPECT_TRUE(estep.reusedObjects());
      for (int i = 0; i < 3; ++i) {
        EXPECT_TRUE(sameBits(estep.downloadQ(i), q_full[static_cast<size_t>(i)])) << "volume " << i;
        if (i > 0) {
          EXPECT_EQ(estep.claimedPixels(i), positiveBounds(q_full[static_cast<size_t>(i)]))
              << "volume " << i;
        }
      }
    }
    EXPECT_THROW(estep.computeBackgroundWeights(d_vertex.get(), volumes, 0), InvalidArgument);
  }
  // A band of rows of q, as the visibility rule downloads it.
  {
    const cv::Mat whole = estep.downloadQ(1);
    const cv::Mat band = estep.downloadQRows(1, 37, 20);
    EXPECT_TRUE(sameBits(band, whole.rowRange(37, 57).clone()));
    EXPECT_EQ(estep.downloadQRows(1, k.height, 0).rows, 0);
    EXPECT_THROW(estep.downloadQRows(1, k.height - 5, 6), InvalidArgument);
    EXPECT_THROW(estep.downloadQRows(1, -1, 2), InvalidArgument);
  }
  // An object seen nowhere (empty rectangle) after one seen: its q is 0 everywhere again, and
  // the others are those of an E-step without it.
  const std::vector<cv::Mat> q_without_1 = eStepReference({host[0], host[2]}, vertex, options);
  estep.compute(d_vertex.get(), {{d_bg.view, nullptr, host[0].T_volume_camera, {}, {}},
                                 {d_1.view, c_1.get(), host[1].T_volume_camera, {}, cv::Rect()},
                                 {d_2.view, c_2.get(), host[2].T_volume_camera, {}, px_2}});
  EXPECT_EQ(cv::countNonZero(estep.downloadQ(1)), 0);
  EXPECT_TRUE(estep.claimedPixels(1).empty());
  EXPECT_EQ(estep.claimedPixels(2), positiveBounds(estep.downloadQ(2)));
  EXPECT_LT(cv::norm(estep.downloadQ(0), q_without_1[0], cv::NORM_INF), kQTolerance);
  EXPECT_LT(cv::norm(estep.downloadQ(2), q_without_1[1], cv::NORM_INF), kQTolerance);
}

INSTANTIATE_TEST_SUITE_P(Association, EStepModes, ::testing::Values("em", "pfg"));

TEST(EStepReference, LikelihoodFollowsTheMethodFormula) {
  // A volume whose SDF is the plane z = 0.5 (psi = 0.5 - z in front of it): points at known
  // distances give alpha/(2 sigma) exp(-|psi|/sigma) + (1-alpha) p_U; outside the grid 0.
  const test::HostVolume plane =
      test::volumeFromSdf([](const Eigen::Vector3f& x) { return 0.5f - x.z(); },
                          Eigen::Vector3i::Constant(8), 0.02f, 0.2f, 5.0f);
  EmOptions o;
  EStepHostVolume vol{plane.view(), Eigen::Isometry3d::Identity(), {}};
  for (const float d : {0.0f, 0.01f, 0.03f, -0.05f}) {
    float abs_psi = 0;
    const float lik =
        associationLikelihood(vol, Eigen::Vector3f(0.61f, 0.65f, 0.5f - d), o, &abs_psi);
    const double expected = o.alpha / (2 * o.sigma_m) * std::exp(-std::fabs(d) / o.sigma_m) +
                            (1 - o.alpha) * o.p_uniform;
    EXPECT_NEAR(abs_psi, std::fabs(d), 2e-4) << d;
    EXPECT_NEAR(lik, expected, 1e-2 * expected) << d;
  }
  float abs_psi = 0;
  EXPECT_EQ(associationLikelihood(vol, Eigen::Vector3f(-0.1f, 0.5f, 0.5f), o, &abs_psi), 0.0f);
  EXPECT_TRUE(std::isnan(abs_psi));
  // A claim box ending at x = 0.6: the point at x = 0.61 is outside it (0, NaN), one at 0.59
  // keeps the formula.
  vol.claim.hi.x() = 0.6f;
  EXPECT_EQ(associationLikelihood(vol, Eigen::Vector3f(0.61f, 0.65f, 0.5f), o, &abs_psi), 0.0f);
  EXPECT_TRUE(std::isnan(abs_psi));
  const double at_surface = o.alpha / (2 * o.sigma_m) + (1 - o.alpha) * o.p_uniform;
  EXPECT_NEAR(associationLikelihood(vol, Eigen::Vector3f(0.59f, 0.65f, 0.5f), o, &abs_psi),
              at_surface, 1e-2 * at_surface);
}

}  // namespace
}  // namespace emf::em
