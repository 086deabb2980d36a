// Each lifecycle rule of docs/method.md#detection-frames and #visibility-and-deletion on a
// constructed case.
#include "em/object_rules.h"

#include <cmath>
#include <random>

#include "test_support.h"

namespace emf::em {
namespace {

constexpr double kIoUGridTolerance = 0.02;      // boxIoU sampling error at n = 24
constexpr double kTruncationToleranceM = 1e-9;  // objectTruncation: exact arithmetic

core::Detection detection(const std::string& cls, cv::Rect box, cv::Size image = {640, 480}) {
  core::Detection d;
  d.class_name = cls;
  d.score = 0.9f;
  d.box = box;
  d.mask = cv::Mat::zeros(image, CV_32F);
  d.mask(box).setTo(1.f);
  return d;
}

TEST(ObjectRules, SizeFilterUsesBothSides) {
  ObjectOptions o;  // 40 px
  EXPECT_EQ(detectionUse(detection("cup", {0, 0, 40, 40}), o), DetectionUse::kUse);
  EXPECT_EQ(detectionUse(detection("cup", {0, 0, 39, 100}), o), DetectionUse::kTooSmall);
  EXPECT_EQ(detectionUse(detection("cup", {0, 0, 100, 39}), o), DetectionUse::kTooSmall);
}

TEST(ObjectRules, PersonOnlyWhenConfigured) {
  ObjectOptions o;
  EXPECT_EQ(detectionUse(detection("person", {0, 0, 80, 200}), o), DetectionUse::kPersonIgnored);
  o.track_person = true;
  EXPECT_EQ(detectionUse(detection("person", {0, 0, 80, 200}), o), DetectionUse::kUse);
}

TEST(ObjectRules, ExcludeListBlocksCreationOnly) {
  ObjectOptions o;
  EXPECT_FALSE(classMayCreate("refrigerator", o));
  EXPECT_FALSE(classMayCreate("dining table", o));
  EXPECT_TRUE(classMayCreate("teddy bear", o));
  EXPECT_EQ(detectionUse(detection("refrigerator", {0, 0, 100, 100}), o), DetectionUse::kUse);
}

TEST(ObjectRules, MaskIoU) {
  cv::Mat a = cv::Mat::zeros(10, 10, CV_8U), b = cv::Mat::zeros(10, 10, CV_8U);
  a(cv::Rect(0, 0, 4, 5)).setTo(1);  // 20 px
  b(cv::Rect(2, 0, 4, 5)).setTo(1);  // 20 px, overlap 10
  EXPECT_DOUBLE_EQ(maskIoU(a, b), 10.0 / 30.0);
  EXPECT_DOUBLE_EQ(maskIoU(a, a), 1.0);
  EXPECT_DOUBLE_EQ(maskIoU(cv::Mat::zeros(3, 3, CV_8U), cv::Mat::zeros(3, 3, CV_8U)), 0.0);
}

TEST(ObjectRules, GreedyMatchingTakesLargestIoUAboveThreshold) {
  // det0 overlaps obj0 (0.5) and obj1 (0.6); det1 overlaps obj1 (0.7); det2 only 0.15.
  const std::vector<std::vector<double>> iou = {{0.5, 0.6}, {0.0, 0.7}, {0.15, 0.0}};
  const std::vector<int> m = matchByIoU(iou, 0.2);
  EXPECT_EQ(m[1], 1);   // the best pair first
  EXPECT_EQ(m[0], 0);   // then det0 takes the remaining object
  EXPECT_EQ(m[2], -1);  // below threshold: unmatched, may create
  EXPECT_TRUE(matchByIoU({}, 0.2).empty());
}

// A 40 x 30 image: object 3 (a "horse", 10 x 10 px at 2 m) and object 5 (a "cup", 4 x 4 px at
// 1.5 m) on the background (id 0) at 3 m; the frame's depth equals the ray cast.
struct SpillScene {
  cv::Mat ids = cv::Mat(30, 40, CV_32S, cv::Scalar(0));
  cv::Mat depth = cv::Mat(30, 40, CV_32F, cv::Scalar(3.0f));
  cv::Mat measured;
  std::vector<MaskObject> objects = {{3, "horse"}, {5, "cup"}};
  SpillScene() {
    ids(cv::Rect(5, 5, 10, 10)).setTo(3);
    depth(cv::Rect(5, 5, 10, 10)).setTo(2.0f);
    ids(cv::Rect(30, 20, 4, 4)).setTo(5);
    depth(cv::Rect(30, 20, 4, 4)).setTo(1.5f);
    measured = depth.clone();
  }
  static cv::Mat mask(cv::Rect r) {
    cv::Mat m(30, 40, CV_8U, cv::Scalar(0));
    m(r).setTo(255);
    return m;
  }
};

constexpr double kMarginM = 0.05;       // objects.render_margin_m
constexpr double kMarginPerM2 = 0.005;  // track.inlier_noise_per_m2

TEST(ObjectRules, AMaskSpilledOverAnUnmatchedObjectOfItsClassShowsThatObject) {
  SpillScene s;
  // The horse's mask spilled over 25 x 20 px (IoU 100 / 500 = 0.2, left unmatched here), and
  // a cup detection that covers the horse too: only the horse's class takes it.
  const std::vector<cv::Mat> masks = {SpillScene::mask(cv::Rect(0, 0, 25, 20)),
                                      SpillScene::mask(cv::Rect(0, 0, 25, 20))};
  const std::vector<std::string> classes = {"cup", "horse"};
  const std::vector<int> spilled = matchSpilledMasks(
      masks, classes, {-1, -1}, s.objects, s.ids, s.depth, s.measured, 0.7, kMarginM, kMarginPerM2);
  EXPECT_EQ(spilled, (std::vector<int>{-1, 0}));
  // Off (share 0), or the horse already matched by IoU: nothing spilled.
  EXPECT_EQ(matchSpilledMasks(masks, classes, {-1, -1}, s.objects, s.ids, s.depth, s.measured, 0.0,
                              kMarginM, kMarginPerM2),
            (std::vector<int>{-1, -1}));
  EXPECT_EQ(matchSpilledMasks(masks, classes, {-1, 0}, s.objects, s.ids, s.depth, s.measured, 0.7,
                              kMarginM, kMarginPerM2),
            (std::vector<int>{-1, -1}));
}

TEST(ObjectRules, ASpilledMaskMustHoldTheShareOfTheObjectThatTheDepthShows) {
  SpillScene s;
  // 60 of the horse's 100 px (rows 5-10) are held: below 0.7, above 0.5.
  const std::vector<cv::Mat> half = {SpillScene::mask(cv::Rect(0, 0, 25, 11))};
  EXPECT_EQ(matchSpilledMasks(half, {"horse"}, {-1}, s.objects, s.ids, s.depth, s.measured, 0.7,
                              kMarginM, kMarginPerM2),
            (std::vector<int>{-1}));
  EXPECT_EQ(matchSpilledMasks(half, {"horse"}, {-1}, s.objects, s.ids, s.depth, s.measured, 0.5,
                              kMarginM, kMarginPerM2),
            (std::vector<int>{0}));
  // Two horse detections hold the whole horse and 60 % of it: the first takes it.
  const std::vector<cv::Mat> two = {SpillScene::mask(cv::Rect(0, 0, 25, 11)),
                                    SpillScene::mask(cv::Rect(0, 0, 25, 20))};
  EXPECT_EQ(matchSpilledMasks(two, {"horse", "horse"}, {-1, -1}, s.objects, s.ids, s.depth,
                              s.measured, 0.5, kMarginM, kMarginPerM2),
            (std::vector<int>{-1, 0}));
}

TEST(ObjectRules, ANewObjectInFrontOfAnOldOneOfItsClassIsNoSpillOverIt) {
  SpillScene s;
  // A second horse stands 0.5 m in front of the first and covers all of it: the frame's depth
  // there is 1.5 m, nearer than the ray cast (2 m) by more than the margin (0.07 m at 2 m).
  s.measured(cv::Rect(3, 3, 14, 14)).setTo(1.5f);
  const std::vector<cv::Mat> masks = {SpillScene::mask(cv::Rect(3, 3, 14, 14))};
  EXPECT_EQ(matchSpilledMasks(masks, {"horse"}, {-1}, s.objects, s.ids, s.depth, s.measured, 0.7,
                              kMarginM, kMarginPerM2),
            (std::vector<int>{-1}));
  // Within the margin (depth noise), the horse is still the one shown.
  s.measured(cv::Rect(3, 3, 14, 14)).setTo(1.95f);
  EXPECT_EQ(matchSpilledMasks(masks, {"horse"}, {-1}, s.objects, s.ids, s.depth, s.measured, 0.7,
                              kMarginM, kMarginPerM2),
            (std::vector<int>{0}));
}

TEST(ObjectRules, ExistenceProbabilityAndDeletion) {
  ObjectOptions o;  // delete below 0.1
  Existence e;      // created by one detection
  EXPECT_DOUBLE_EQ(e.probability(), 1.0);
  for (int i = 0; i < 9; ++i) e.non_ex += 1;  // 1 / 10 = 0.1: kept
  EXPECT_DOUBLE_EQ(e.probability(), 0.1);
  EXPECT_FALSE(e.shouldDelete(o));
  e.non_ex += 1;  // 1 / 11 < 0.1: deleted
  EXPECT_TRUE(e.shouldDelete(o));
}

TEST(ObjectRules, PlacementFromPercentilesWithPadding) {
  // Uniform points in a 0.2 x 0.1 x 0.05 box centred at (1, 2, 3): the 10th-90th percentile
  // range is 80% of each side, so the edge is 0.8 * 0.2 * padding 2 = 0.32 m.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector3d r = test::drawXyz<Eigen::Vector3d>([&] { return u(rng); });
    pts.emplace_back(1 + 0.2 * r.x(), 2 + 0.1 * r.y(), 3 + 0.05 * r.z());
  }
  ObjectOptions o;
  const VolumePlacement p = placeObject(pts, o);
  EXPECT_NEAR(p.centre_world.x(), 1.0, 2e-3);
  EXPECT_NEAR(p.centre_world.y(), 2.0, 2e-3);
  EXPECT_NEAR(p.centre_world.z(), 3.0, 2e-3);
  EXPECT_NEAR(p.extent_m, 0.32, 3e-3);
  EXPECT_EQ(p.resolution, 64);
  EXPECT_NEAR(p.voxel_size_m, 0.32 / 64, 1e-4);
  EXPECT_EQ(placeObject({{0, 0, 0}}, o).extent_m, 0.0);
}

TEST(ObjectRules, ClaimRegionWidensTheShownBoxAndStretchesItAwayFromTheCamera) {
  // A 1 m x 0.5 m patch at z = 2 facing the camera, points every cm: per axis the 2nd-98th
  // percentiles are x 0.02-0.98, y 0.01-0.49, z 2; the largest 10th-90th extent is 0.8 (x).
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i <= 100; ++i) {
    for (int j = 0; j <= 50; ++j) pts.emplace_back(0.01 * i, 0.01 * j, 2.0);
  }
  const Eigen::Vector3d camera(0.5, 0.25, 0.0);  // looks along +z at the patch's centre
  ObjectOptions o;
  o.claim_margin = 0.5;  // 0.4 m on every side
  o.claim_depth = 1.0;   // 0.8 m further away from the camera
  const Eigen::AlignedBox3d box = claimRegion(pts, camera, o);
  constexpr double kTol = 1e-9;
  EXPECT_NEAR(box.min().x(), 0.02 - 0.4, kTol);
  EXPECT_NEAR(box.max().x(), 0.98 + 0.4, kTol);
  EXPECT_NEAR(box.min().y(), 0.01 - 0.4, kTol);
  EXPECT_NEAR(box.max().y(), 0.49 + 0.4, kTol);
  EXPECT_NEAR(box.min().z(), 2.0 - 0.4, kTol);  // nothing is added towards the camera
  EXPECT_NEAR(box.max().z(), 2.0 + 0.4 + 0.8, kTol);
  // Seen from the other side, the region grows towards -z instead.
  const Eigen::AlignedBox3d behind = claimRegion(pts, Eigen::Vector3d(0.5, 0.25, 4.0), o);
  EXPECT_NEAR(behind.min().z(), 2.0 - 0.4 - 0.8, kTol);
  EXPECT_NEAR(behind.max().z(), 2.0 + 0.4, kTol);
  // No margin, no depth: the shown box itself.
  o.claim_margin = 0.0;
  o.claim_depth = 0.0;
  const Eigen::AlignedBox3d shown = claimRegion(pts, camera, o);
  EXPECT_NEAR(shown.min().x(), 0.02, kTol);
  EXPECT_NEAR(shown.max().z(), 2.0, kTol);
  // Fewer than 10 points: empty (the object keeps its whole volume until a detection shows it).
  EXPECT_TRUE(claimRegion({pts.begin(), pts.begin() + 9}, camera, o).isEmpty());
}

TEST(ObjectRules, BoxIoU) {
  OrientedBox a, b;
  a.size_m = b.size_m = Eigen::Vector3d(1, 1, 1);
  EXPECT_NEAR(boxIoU(a, b), 1.0, 1e-12);
  b.T_world_box.translation() = Eigen::Vector3d(0.5, 0, 0);  // overlap 0.5: IoU 1/3
  EXPECT_NEAR(boxIoU(a, b), 1.0 / 3.0, kIoUGridTolerance);
  b.T_world_box.translation() = Eigen::Vector3d(2, 0, 0);
  EXPECT_DOUBLE_EQ(boxIoU(a, b), 0.0);
  // Rotated by 90 deg about the box's own centre: same region.
  OrientedBox c = a;
  c.T_world_box = Eigen::Translation3d(0.5, 0.5, 0.5) *
                  Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()) *
                  Eigen::Translation3d(-0.5, -0.5, -0.5);
  EXPECT_NEAR(boxIoU(a, c), 1.0, kIoUGridTolerance);
}

/// Camera-frame vertex map (CV_32FC4, w = 1) of a pinhole camera (f 100 px, centre of the
/// image) looking at per-pixel depths z (CV_32F, <= 0: invalid, w = 0).
cv::Mat vertexMap(const cv::Mat& z) {
  cv::Mat vertex(z.size(), CV_32FC4, cv::Scalar::all(0));
  for (int v = 0; v < z.rows; ++v) {
    for (int u = 0; u < z.cols; ++u) {
      const float d = z.at<float>(v, u);
      if (d <= 0.f) continue;
      vertex.at<cv::Vec4f>(v, u) = {(u - 0.5f * z.cols) / 100.f * d,
                                    (v - 0.5f * z.rows) / 100.f * d, d, 1.f};
    }
  }
  return vertex;
}

std::vector<Eigen::Vector3d> pointsUnder(const cv::Mat& mask, const cv::Mat& vertex) {
  std::vector<Eigen::Vector3d> pts;
  for (int v = 0; v < mask.rows; ++v) {
    for (int u = 0; u < mask.cols; ++u) {
      const cv::Vec4f& p = vertex.at<cv::Vec4f>(v, u);
      if (mask.at<float>(v, u) > 0.5f && p[3] != 0.f) pts.emplace_back(p[0], p[1], p[2]);
    }
  }
  return pts;
}

TEST(ObjectRules, CreationMaskDropsWhatSpillsOverTheSilhouette) {
  // A 20x20 px object 2 m away, slanted (1 mm per px) with +-1 cm noise, in front of a wall at
  // 3 m; one pixel inside it has no depth. The detector's mask is the object dilated by 3 px
  // (p_fg 0.8), so 276 of its 676 pixels lie on the wall across a 1 m depth jump.
  const cv::Rect object(30, 20, 20, 20);
  cv::Mat z(60, 80, CV_32F, cv::Scalar(3.0f));
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> noise(-0.01f, 0.01f);
  for (int v = object.y; v < object.br().y; ++v) {
    for (int u = object.x; u < object.br().x; ++u)
      z.at<float>(v, u) = 2.0f + 0.001f * u + noise(rng);
  }
  z.at<float>(30, 40) = 0.f;
  const cv::Mat vertex = vertexMap(z);
  cv::Mat mask = cv::Mat::zeros(z.size(), CV_32F);
  mask(cv::Rect(object.x - 3, object.y - 3, object.width + 6, object.height + 6)).setTo(0.8f);

  ObjectOptions o;  // 3 cm + 1 cm/m^2 x z^2: 7 cm at 2 m
  const cv::Mat kept = creationMask(mask, vertex, o);
  ASSERT_EQ(kept.size(), mask.size());
  ASSERT_EQ(kept.type(), CV_32F);
  // Every object pixel with depth but the 4 corners (the silhouette rim joins through its inner
  // neighbours; a corner's inner neighbours are rim pixels), no wall pixel.
  EXPECT_EQ(cv::countNonZero(kept), object.area() - 1 - 4);
  EXPECT_EQ(cv::countNonZero(kept(object)), object.area() - 1 - 4);
  EXPECT_EQ(kept.at<float>(30, 40), 0.f);
  double lo = 0, hi = 0;
  cv::minMaxLoc(kept, &lo, &hi, nullptr, nullptr, kept > 0.f);
  EXPECT_FLOAT_EQ(static_cast<float>(lo), 0.8f);  // p_fg carried over
  EXPECT_FLOAT_EQ(static_cast<float>(hi), 0.8f);

  // Why: the wall pixels put the 90th depth percentile on the wall, so the volume would be
  // built 2 x 1 m deep; from the kept pixels it is 2 x the object's 10th-90th extent.
  const VolumePlacement spilled = placeObject(pointsUnder(mask, vertex), o);
  const VolumePlacement refined = placeObject(pointsUnder(kept, vertex), o);
  EXPECT_GT(spilled.extent_m, 1.9);
  const double object_width_m = object.width / 100.0 * 2.0;  // 0.4 m at 2 m
  EXPECT_LT(refined.extent_m, 2.0 * object_width_m);
  EXPECT_GT(refined.extent_m, 2.0 * 0.7 * object_width_m);

  // Off: the whole mask.
  o.creation_depth_jump_m = 0.0;
  EXPECT_EQ(cv::countNonZero(creationMask(mask, vertex, o) != mask), 0);
}

TEST(ObjectRules, CreationMaskKeepsTheLargestContinuousPart) {
  // A continuous floor seen at 1.5-2.5 m under the whole mask keeps every pixel with depth; a
  // second object behind a jump keeps only the larger part.
  cv::Mat z(60, 80, CV_32F);
  for (int v = 0; v < z.rows; ++v) z.row(v).setTo(2.5f - v / 60.f);
  ObjectOptions o;
  cv::Mat mask = cv::Mat::zeros(z.size(), CV_32F);
  mask(cv::Rect(10, 10, 50, 40)).setTo(1.f);
  EXPECT_EQ(cv::countNonZero(creationMask(mask, vertexMap(z), o)), 50 * 40);

  z(cv::Rect(10, 10, 50, 10)).setTo(4.0f);  // rows 10-19 jump back to 4 m
  const cv::Mat kept = creationMask(mask, vertexMap(z), o);
  // Rows 20-49 (row 20 borders the jump, and joins through row 21); rows 10-19 are the
  // smaller part.
  EXPECT_EQ(cv::countNonZero(kept), 50 * 30);
  EXPECT_EQ(cv::countNonZero(kept(cv::Rect(10, 10, 50, 10))), 0);
}

TEST(ObjectRules, ObjectTruncationInVoxelsWithAPixelFloorAndTheMapsCap) {
  ObjectOptions o;
  o.truncation_voxels = 5.0;  // at least 4 pixel footprints (the default)
  const double map_voxels = 10.0;
  // A car 2.3 m away with 1 cm voxels at 320x240 (fx 262.5: 0.88 cm per pixel): 5 voxels.
  EXPECT_NEAR(objectTruncation(o, map_voxels, 0.01, 2.3 / 262.5), 0.05, kTruncationToleranceM);
  // At 160x120 (1.75 cm per pixel) with 0.57 cm voxels: 4 footprints would be 7 cm, above the
  // map's 10 voxels (5.7 cm), which cap it.
  EXPECT_NEAR(objectTruncation(o, map_voxels, 0.0057, 2.3 / 131.25), 0.057, kTruncationToleranceM);
  // Between the two: 1 cm voxels, 1.5 cm per pixel -> 4 footprints, 6 cm.
  EXPECT_NEAR(objectTruncation(o, map_voxels, 0.01, 0.015), 0.06, kTruncationToleranceM);
  // The paper's setting: truncation_voxels = map's, no pixel floor.
  o.truncation_voxels = map_voxels;
  o.truncation_min_px = 0.0;
  EXPECT_NEAR(objectTruncation(o, map_voxels, 0.0057, 0.0175), 0.057, kTruncationToleranceM);
}

TEST(ObjectRules, ObjectVolumeSpecCarriesTheObjectsIntegrationRules) {
  ObjectOptions o;
  map::MapOptions m;
  VolumePlacement p;
  p.resolution = 64;
  p.voxel_size_m = 0.01;
  p.extent_m = 0.64;
  const map::VolumeSpec a = objectVolumeSpec(m, o, p, 2.3 / 262.5);
  EXPECT_EQ(a.dims_blocks, Eigen::Vector3i(8, 8, 8));
  EXPECT_FLOAT_EQ(a.voxel_size_m, 0.01f);
  EXPECT_NEAR(a.truncation_m, objectTruncation(o, m.truncation_voxels, 0.01, 2.3 / 262.5),
              kTruncationToleranceM + 1e-8);  // stored as float
  EXPECT_TRUE(a.has_counts);
  EXPECT_FALSE(a.free_space_full_weight);
  EXPECT_FALSE(a.behind_dropoff);
  // The objects' weight cap, not the background's.
  EXPECT_FLOAT_EQ(a.max_weight, 127.0f);
  EXPECT_FLOAT_EQ(map::VolumeSpec::background(m).max_weight, 64.0f);
  o.free_space_full_weight = true;
  o.behind_dropoff = true;
  o.max_weight = 20.0;
  const map::VolumeSpec b = objectVolumeSpec(m, o, p, 2.3 / 262.5);
  EXPECT_TRUE(b.free_space_full_weight);
  EXPECT_TRUE(b.behind_dropoff);
  EXPECT_FLOAT_EQ(b.max_weight, 20.0f);
}

TEST(ObjectRules, CreationChecks) {
  ObjectOptions o;
  core::Detection d = detection("cup", {100, 100, 100, 100});
  VolumePlacement p;
  p.centre_world = Eigen::Vector3d(0, 0, 2);
  p.extent_m = 0.4;
  p.voxel_size_m = 0.4 / 64;
  p.resolution = 64;
  const Eigen::Vector3d cam(0, 0, 0);
  cv::Mat ids = cv::Mat::zeros(480, 640, CV_32S);
  std::string why;
  EXPECT_TRUE(mayCreate(d, p, cam, {}, ids, o, &why)) << why;

  VolumePlacement far = p;
  far.centre_world.z() = 5.5;
  EXPECT_FALSE(mayCreate(d, far, cam, {}, ids, o, &why));
  EXPECT_NE(why.find("max_create_distance_m"), std::string::npos);

  OrientedBox same;  // the same cube already exists
  same.size_m = Eigen::Vector3d::Constant(0.4);
  same.T_world_box.translation() = p.centre_world - Eigen::Vector3d::Constant(0.2);
  EXPECT_FALSE(mayCreate(d, p, cam, {same}, ids, o, &why));
  EXPECT_NE(why.find("volume IoU"), std::string::npos);
  OrientedBox shifted = same;  // overlap 1/3 < 0.5: allowed
  shifted.T_world_box.translation().x() += 0.2;
  EXPECT_TRUE(mayCreate(d, p, cam, {shifted}, ids, o, &why)) << why;

  ids(cv::Rect(100, 100, 60, 100)).setTo(3);  // 60% of the mask covered by object 3
  EXPECT_FALSE(mayCreate(d, p, cam, {}, ids, o, &why));
  EXPECT_NE(why.find("covered"), std::string::npos);
  ids.setTo(0);
  ids(cv::Rect(100, 100, 40, 100)).setTo(3);  // 40%: allowed
  EXPECT_TRUE(mayCreate(d, p, cam, {}, ids, o, &why)) << why;

  EXPECT_FALSE(mayCreate(detection("oven", {100, 100, 100, 100}), p, cam, {}, ids, o, &why));
  EXPECT_NE(why.find("exclude_classes"), std::string::npos);

  // A box that passes the size filter but lies half in the 20 px border band: 40 x 40 at the
  // left edge leaves 20 x 40 = 800 visible px < 1600: deleted at once, so not created.
  const core::Detection edge = detection("cup", {0, 200, 40, 40});
  EXPECT_EQ(detectionUse(edge, o), DetectionUse::kUse);
  EXPECT_EQ(maskVisiblePixels(edge.mask, o), 20 * 40);
  EXPECT_FALSE(mayCreate(edge, p, cam, {}, ids, o, &why));
  EXPECT_NE(why.find("invisible_min_px"), std::string::npos) << why;
  // Mask values at or below 0.5 are not the object's.
  core::Detection faint = d;
  faint.mask = d.mask.clone();  // (a copied Detection shares d's pixels)
  faint.mask *= 0.5f;
  EXPECT_EQ(maskVisiblePixels(faint.mask, o), 0);
  EXPECT_FALSE(mayCreate(faint, p, cam, {}, ids, o, &why));
  EXPECT_EQ(maskVisiblePixels(d.mask, o), 100 * 100);
}

TEST(ObjectRules, VisibilityIgnoresBorder) {
  ObjectOptions o;                    // 1600 px inside the image shrunk by 20 px
  o.invisible_inside_fraction = 0.0;  // the paper's rule
  cv::Mat ids = cv::Mat::zeros(480, 640, CV_16U);
  ids(cv::Rect(0, 0, 60, 60)).setTo(2);  // 3600 px, but only 40x40 = 1600 inside the border
  EXPECT_EQ(visiblePixels(ids, 2, o), 1600);
  EXPECT_FALSE(isInvisible(ids, 2, o));
  ids.setTo(0);
  ids(cv::Rect(0, 0, 59, 60)).setTo(2);  // 39 x 40 = 1560 inside
  EXPECT_EQ(visiblePixels(ids, 2, o), 1560);
  EXPECT_TRUE(isInvisible(ids, 2, o));
  EXPECT_TRUE(isInvisible(ids, 7, o));  // not rendered at all
}

TEST(ObjectRules, SmallObjectInsideTheBorderStaysVisible) {
  ObjectOptions o;  // 1600 px, 20 px border, inside fraction 0.9
  ASSERT_GT(o.invisible_inside_fraction, 0.0);
  cv::Mat ids = cv::Mat::zeros(480, 640, CV_16U);
  ids(cv::Rect(300, 200, 20, 20)).setTo(3);  // 400 px, all inside: small, not leaving
  EXPECT_EQ(visiblePixels(ids, 3, o), 400);
  EXPECT_FALSE(isInvisible(ids, 3, o));
  ids.setTo(0);
  ids(cv::Rect(10, 200, 20, 20)).setTo(3);  // half in the border band: 200 of 400 inside
  EXPECT_EQ(visiblePixels(ids, 3, o), 200);
  EXPECT_TRUE(isInvisible(ids, 3, o));
  ids.setTo(0);
  ids(cv::Rect(18, 200, 20, 20)).setTo(3);  // 2 of 20 columns in the band: 360 of 400 = 0.9
  EXPECT_FALSE(isInvisible(ids, 3, o));
  ids.setTo(0);
  ids(cv::Rect(17, 200, 20, 20)).setTo(3);  // 3 columns: 340 of 400 = 0.85 < 0.9
  EXPECT_TRUE(isInvisible(ids, 3, o));
  EXPECT_TRUE(isInvisible(ids, 7, o));  // not rendered at all
  o.invisible_inside_fraction = 0.0;    // the paper: small is invisible
  ids.setTo(0);
  ids(cv::Rect(300, 200, 20, 20)).setTo(3);
  EXPECT_TRUE(isInvisible(ids, 3, o));
}

TEST(ObjectRules, MeanAssociationOverMask) {
  cv::Mat ids = cv::Mat::zeros(10, 10, CV_32S);
  ids(cv::Rect(0, 0, 5, 2)).setTo(1);  // 10 px
  cv::Mat q = cv::Mat::zeros(10, 10, CV_32F);
  q(cv::Rect(0, 0, 5, 1)).setTo(0.3f);  // 5 px at 0.3
  q(cv::Rect(0, 1, 5, 1)).setTo(0.1f);  // 5 px at 0.1
  q(cv::Rect(5, 5, 5, 5)).setTo(1.0f);  // outside the mask: ignored
  EXPECT_NEAR(meanAssociation(q, ids, 1), 0.2, 1e-6);
  EXPECT_EQ(meanAssociation(q, ids, 4), 0.0);
}

TEST(ObjectRules, LostTooLongAfterMaxLostFrames) {
  ObjectOptions o;
  o.max_lost_frames = 15;
  EXPECT_FALSE(lostTooLong(0, o));
  EXPECT_FALSE(lostTooLong(15, o));  // "more than" 15 frames
  EXPECT_TRUE(lostTooLong(16, o));
  o.max_lost_frames = 0;  // off
  EXPECT_FALSE(lostTooLong(100000, o));
}

TEST(ObjectRules, PoseChangeMeasuresTheCentreAndTheAngle) {
  constexpr double kTolerance = 1e-12;
  const Eigen::Vector3d centre(0.3, 0.3, 0.3);  // volume frame, m
  Eigen::Isometry3d a = Eigen::Isometry3d::Identity();
  a.translation() = Eigen::Vector3d(1, 2, 3);
  // 10 deg about the vertical through the centre: the centre stays, the angle is 10 deg.
  const Eigen::Isometry3d turn = Eigen::Translation3d(a * centre) *
                                 Eigen::AngleAxisd(10.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()) *
                                 Eigen::Translation3d(-(a * centre));
  PoseChange c = poseChange(a, turn * a, centre);
  EXPECT_NEAR(c.centre_m, 0.0, kTolerance);
  EXPECT_NEAR(c.angle_deg, 10.0, kTolerance);
  // 2 cm along x in the world: the centre moves 2 cm, no angle.
  const Eigen::Isometry3d shift(Eigen::Translation3d(0.02, 0, 0));
  c = poseChange(a, shift * a, centre);
  EXPECT_NEAR(c.centre_m, 0.02, kTolerance);
  EXPECT_NEAR(c.angle_deg, 0.0, kTolerance);
}

TEST(ObjectRules, AHeldObjectStartsMovingWhenItsOffsetGrowsFrameAfterFrame) {
  ObjectOptions o;
  o.still_translation_m = 0.02;  // a quarter: 5 mm
  o.still_rotation_deg = 2.0;    // half: 1 deg
  // Offsets of the centre (m) with a jittering angle, and of the angle (deg) with the centre put.
  const auto moved = [](std::vector<double> m) {
    std::vector<PoseChange> c;
    for (size_t i = 0; i < m.size(); ++i) c.push_back({m[i], i % 2 ? 0.3 : 0.1});
    return c;
  };
  const auto turned = [](std::vector<double> deg) {
    std::vector<PoseChange> c;
    for (size_t i = 0; i < deg.size(); ++i) c.push_back({i % 2 ? 0.003 : 0.001, deg[i]});
    return c;
  };
  // A push: 2, 4, 6 mm over three frames after 1 mm.
  EXPECT_TRUE(startsMoving(moved({0.001, 0.002, 0.004, 0.006}), o));
  // Too few frames, a jitter that falls back once, or growth that stays below 5 mm: held.
  EXPECT_FALSE(startsMoving(moved({0.002, 0.004, 0.006}), o));
  EXPECT_FALSE(startsMoving(moved({0.001, 0.004, 0.003, 0.006}), o));
  EXPECT_FALSE(startsMoving(moved({0.001, 0.002, 0.003, 0.0045}), o));
  // A spin in place: 0.4, 0.7, 1.1 deg after 0.2; likewise held below 1 deg or on a jitter.
  EXPECT_TRUE(startsMoving(turned({0.2, 0.4, 0.7, 1.1}), o));
  EXPECT_FALSE(startsMoving(turned({0.2, 0.4, 0.7, 0.9}), o));
  EXPECT_FALSE(startsMoving(turned({0.2, 0.7, 0.4, 1.1}), o));
  // Off without still objects.
  o.still_translation_m = 0.0;
  EXPECT_FALSE(startsMoving(moved({0.001, 0.002, 0.004, 0.006}), o));
  EXPECT_FALSE(startsMoving(turned({0.2, 0.4, 0.7, 1.1}), o));
}

TEST(ObjectRules, StillOnceEveryPoseOfTheWindowIsWithinTheBounds) {
  ObjectOptions o;
  o.still_translation_m = 0.01;
  o.still_rotation_deg = 1.0;
  o.still_frames = 15;
  const Eigen::Vector3d centre(0.3, 0.3, 0.3);
  // The volume pose with its centre moved x_m along x and turned yaw_deg about it.
  const auto at = [&](double x_m, double yaw_deg) {
    return Eigen::Isometry3d(Eigen::Translation3d(Eigen::Vector3d(x_m, 0, 2) + centre) *
                             Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitY()) *
                             Eigen::Translation3d(-centre));
  };
  // Jitter of 4 mm and 0.4 deg about a pose: still once 15 poses are there, not before.
  std::vector<Eigen::Isometry3d> window;
  for (int i = 0; i < 15; ++i) {
    window.push_back(at(i % 2 ? 0.004 : -0.004, i % 3 ? 0.4 : -0.4));
    EXPECT_EQ(looksStill(window, centre, o), i == 14) << i;
  }
  // A slow push of 1 mm per frame: 14 mm over the window, not still.
  std::vector<Eigen::Isometry3d> push;
  for (int i = 0; i < 15; ++i) push.push_back(at(0.001 * i, 0.0));
  EXPECT_FALSE(looksStill(push, centre, o));
  // A turn of 0.1 deg per frame: 1.4 deg over the window, not still.
  std::vector<Eigen::Isometry3d> turn;
  for (int i = 0; i < 15; ++i) turn.push_back(at(0.0, 0.1 * i));
  EXPECT_FALSE(looksStill(turn, centre, o));
  // Held: released by a pose 1.1 cm or 1.1 deg away, not by one within the bounds.
  EXPECT_TRUE(isStillAt(at(0, 0), at(0.009, 0.9), centre, o));
  EXPECT_FALSE(isStillAt(at(0, 0), at(0.011, 0.0), centre, o));
  EXPECT_FALSE(isStillAt(at(0, 0), at(0.0, 1.1), centre, o));
  // Off (the paper): never still.
  o.still_translation_m = 0.0;
  EXPECT_FALSE(looksStill(window, centre, o));
}

TEST(ObjectRules, AHeldObjectStaysHeldWhileItsTrackedPoseBarelyFitsBetter) {
  ObjectOptions o;
  o.still_release_cost = 0.1;
  // Costs in any common unit: the held pose's cost and its excess over the tracked pose's.
  // A far object's tracked pose 5 % better than the held one (cost 100 there, 105 held): held.
  EXPECT_TRUE(fitKeepsStill(5.0, 105.0, 900, 1000, o));
  // A moved object: the held pose costs 50 % more (or exactly the bound): released.
  EXPECT_FALSE(fitKeepsStill(50.0, 150.0, 900, 1000, o));
  EXPECT_FALSE(fitKeepsStill(10.0, 110.0, 900, 1000, o));
  // Fewer than half the tracked pose's pixels land on the model at the held pose: released.
  EXPECT_FALSE(fitKeepsStill(5.0, 105.0, 499, 1000, o));
  EXPECT_TRUE(fitKeepsStill(5.0, 105.0, 500, 1000, o));
  // Nothing to compare (no pixels, no cost): released, as by the bounds alone.
  EXPECT_FALSE(fitKeepsStill(0.0, 0.0, 0, 0, o));
  EXPECT_FALSE(fitKeepsStill(0.0, 0.0, 900, 1000, o));
  // Off: the bounds alone decide.
  o.still_release_cost = 0.0;
  EXPECT_FALSE(fitKeepsStill(5.0, 105.0, 900, 1000, o));
}

TEST(ObjectRules, OcclusionCountsRenderedPixelsBehindNearerMeasurements) {
  // An object rendered at 2 m on a 4x3 patch; margin 0.05 m + 0.01 z^2 = 0.09 m at 2 m.
  cv::Mat rendered(6, 8, CV_32F, cv::Scalar(NAN));
  rendered(cv::Rect(2, 1, 4, 3)).setTo(2.0f);
  cv::Mat measured(6, 8, CV_32F, cv::Scalar(2.0f));
  measured.at<float>(1, 2) = 1.0f;   // far in front: hidden
  measured.at<float>(1, 3) = 1.90f;  // 0.10 m in front: hidden
  measured.at<float>(1, 4) = 1.92f;  // 0.08 m in front, within the margin: not hidden
  measured.at<float>(1, 5) = 2.5f;   // behind the object: not hidden (it moved away)
  measured.at<float>(2, 2) = NAN;    // no measurement: not hidden
  measured.at<float>(0, 0) = 0.5f;   // in front, but the object is not rendered there
  cv::Mat mask;
  const Occlusion occ = occlusion(rendered, measured, 0.05, 0.01, &mask);
  EXPECT_EQ(occ.rendered, 12);
  EXPECT_EQ(occ.hidden, 2);
  EXPECT_NEAR(occ.hiddenFraction(), 2.0 / 12.0, 1e-12);
  EXPECT_EQ(cv::countNonZero(mask), 2);
  EXPECT_EQ(mask.at<uint8_t>(1, 2), 255);
  EXPECT_EQ(mask.at<uint8_t>(1, 3), 255);
  EXPECT_EQ(mask.at<uint8_t>(1, 4), 0);
  EXPECT_EQ(occ.seen_through, 1);  // (1, 5): 0.5 m behind the surface

  ObjectOptions o;
  o.hidden_fraction = 0.5;
  EXPECT_FALSE(isHidden(occ, o));
  measured(cv::Rect(2, 2, 4, 2)).setTo(1.0f);  // 8 more in front (one was NaN): 10 of 12
  const Occlusion covered = occlusion(rendered, measured, 0.05, 0.01);
  EXPECT_EQ(covered.hidden, 10);
  EXPECT_TRUE(isHidden(covered, o));
  // Hysteresis: once hidden, the object stays hidden until fewer than visible_again_fraction
  // of its pixels are (2 of 12 = 0.17 here).
  o.visible_again_fraction = 0.1;
  EXPECT_FALSE(isHidden(occ, o, false));
  EXPECT_TRUE(isHidden(occ, o, true));
  o.visible_again_fraction = 0.2;
  EXPECT_FALSE(isHidden(occ, o, true));
  o.visible_again_fraction = 0.9;  // capped at hidden_fraction
  EXPECT_TRUE(isHidden(covered, o, true));
  o.hidden_fraction = 0.0;  // off (the paper)
  EXPECT_FALSE(isHidden(covered, o));
  EXPECT_FALSE(isHidden(covered, o, true));
  o.hidden_fraction = 0.5;
  EXPECT_FALSE(isHidden(Occlusion{}, o));  // nothing rendered
}

TEST(ObjectRules, AnObjectMovedOnWhenMostOfItsUnhiddenPartIsSeenThrough) {
  // 20 pixels rendered at 2 m; margin 0.05 m + 0.01 z^2 = 0.09 m at 2 m.
  cv::Mat rendered(4, 5, CV_32F, cv::Scalar(2.0f));
  cv::Mat measured(4, 5, CV_32F, cv::Scalar(2.0f));
  measured.rowRange(0, 2).setTo(1.0f);  // 10 hidden behind an occluder
  measured.at<float>(2, 0) = 2.2f;      // 1 seen through (0.2 m behind), at a silhouette
  Occlusion occ = occlusion(rendered, measured, 0.05, 0.01);
  ASSERT_EQ(occ.hidden, 10);
  ASSERT_EQ(occ.seen_through, 1);
  EXPECT_FALSE(movedOn(occ));                  // its visible part is where the model says
  measured(cv::Rect(0, 2, 4, 1)).setTo(3.0f);  // 4 of the 10 unhidden see the wall behind
  occ = occlusion(rendered, measured, 0.05, 0.01);
  ASSERT_EQ(occ.seen_through, 4);
  EXPECT_FALSE(movedOn(occ));       // fewer than half of the unhidden 10
  measured.at<float>(3, 0) = 3.0f;  // 5 of 10: half
  occ = occlusion(rendered, measured, 0.05, 0.01);
  ASSERT_EQ(occ.seen_through, 5);
  EXPECT_TRUE(movedOn(occ));
  // Almost wholly hidden: one seen-through pixel of the two in front is a silhouette, under a
  // tenth of what it renders.
  measured.setTo(1.0f);
  measured.at<float>(3, 3) = 3.0f;
  measured.at<float>(3, 4) = 2.0f;
  occ = occlusion(rendered, measured, 0.05, 0.01);
  ASSERT_EQ(occ.hidden, 18);
  ASSERT_EQ(occ.seen_through, 1);
  EXPECT_FALSE(movedOn(occ));
  EXPECT_FALSE(movedOn(Occlusion{}));  // nothing rendered
}

TEST(ObjectRules, StaleBackgroundGivesPixelsBackWhereTheDepthSeesThroughIt) {
  // The background's copy of a chair's old surface at 2.4 m covers a 4x3 patch (id 0); the
  // chair (id 3) now stands 0.2 m behind it. Margin 0.05 m + 0.005 z^2 = 0.0788 m at 2.6 m.
  cv::Mat ids(5, 8, CV_32S, cv::Scalar(-1));
  cv::Mat depth(5, 8, CV_32F, cv::Scalar(NAN));
  ids(cv::Rect(2, 1, 4, 3)).setTo(0);
  depth(cv::Rect(2, 1, 4, 3)).setTo(2.4f);
  cv::Mat object_ids(5, 8, CV_32S, cv::Scalar(-1));
  cv::Mat object_depth(5, 8, CV_32F, cv::Scalar(NAN));
  object_ids(cv::Rect(2, 1, 4, 3)).setTo(3);
  object_depth(cv::Rect(2, 1, 4, 3)).setTo(2.6f);
  cv::Mat measured(5, 8, CV_32F, cv::Scalar(2.6f));
  measured.at<float>(1, 2) = 2.4f;   // the background is really there: kept
  measured.at<float>(1, 3) = 2.45f;  // within the margin of the background: kept
  measured.at<float>(1, 4) = 3.2f;   // through the background, but not on the chair: kept
  measured.at<float>(1, 5) = NAN;    // no measurement: kept
  measured.at<float>(2, 2) = 2.53f;  // 0.07 m off the chair, within the margin: the chair's
  const cv::Mat before = ids.clone();
  cv::Mat out = ids.clone();
  EXPECT_EQ(uncoverStaleBackground(&out, depth, object_ids, object_depth, measured, 0.05, 0.005),
            8);
  for (int v = 0; v < 5; ++v) {
    for (int u = 0; u < 8; ++u) {
      const bool given = v >= 2 && v <= 3 && u >= 2 && u <= 5;
      EXPECT_EQ(out.at<int>(v, u), given ? 3 : before.at<int>(v, u)) << u << "," << v;
    }
  }
  // A pixel already the object's, or with no object behind the background, is left alone.
  out = ids.clone();
  out.at<int>(2, 2) = 3;
  object_ids.at<int>(3, 5) = -1;
  object_depth.at<float>(3, 5) = NAN;
  EXPECT_EQ(uncoverStaleBackground(&out, depth, object_ids, object_depth, measured, 0.05, 0.005),
            6);
  EXPECT_EQ(out.at<int>(3, 5), 0);
  // Without the depth-dependent part the margin is 5 cm: 2.53 m is 7 cm off the chair.
  object_ids.at<int>(3, 5) = 3;
  object_depth.at<float>(3, 5) = 2.6f;
  out = ids.clone();
  EXPECT_EQ(uncoverStaleBackground(&out, depth, object_ids, object_depth, measured, 0.05, 0.0), 7);
  EXPECT_EQ(out.at<int>(2, 2), 0);
}

TEST(ObjectRules, HiddenTooLongAfterMaxHiddenFrames) {
  ObjectOptions o;
  o.max_hidden_frames = 300;
  EXPECT_FALSE(hiddenTooLong(300, o));
  EXPECT_TRUE(hiddenTooLong(301, o));
  o.max_hidden_frames = 0;  // never
  EXPECT_FALSE(hiddenTooLong(100000, o));
}

TEST(ObjectRules, LeavingWhenMostOfTheProjectionIsOutsideTheImage) {
  // A wide cast of 16x12 with the frame's rectangle 8x6 in its middle; the object (id 3) is a
  // 6x4 patch straddling the frame's left edge: 2 of its 6 columns inside, 8 of 24 pixels.
  const cv::Rect frame(4, 3, 8, 6);
  cv::Mat wide(12, 16, CV_32S, cv::Scalar(-1));
  wide(cv::Rect(0, 4, 6, 4)).setTo(3);
  wide.at<int>(0, 0) = 5;  // another object: not counted
  EXPECT_NEAR(inViewFraction(wide, 3, frame), 8.0 / 24.0, 1e-12);
  EXPECT_NEAR(inViewFraction(wide, 7, frame), 1.0, 0.0);  // nothing rendered
  wide(cv::Rect(0, 4, 6, 4)).setTo(-1);
  wide(cv::Rect(5, 4, 6, 4)).setTo(3);  // inside the frame
  EXPECT_NEAR(inViewFraction(wide, 3, frame), 1.0, 1e-12);

  // The frame's own cast: only an object on its outermost rows or columns can be cut.
  cv::Mat ids(6, 8, CV_32S, cv::Scalar(-1));
  ids(cv::Rect(1, 1, 6, 4)).setTo(3);
  EXPECT_FALSE(touchesImageEdge(ids, 3));
  for (const cv::Point& edge :
       {cv::Point(0, 2), cv::Point(7, 2), cv::Point(3, 0), cv::Point(3, 5)}) {
    cv::Mat cut = ids.clone();
    cut.at<int>(edge) = 3;
    EXPECT_TRUE(touchesImageEdge(cut, 3)) << edge;
    EXPECT_FALSE(touchesImageEdge(cut, 4)) << edge;
  }

  ObjectOptions o;
  o.leaving_fraction = 0.5;
  o.in_view_again_fraction = 0.6;
  EXPECT_TRUE(isLeaving(0.49, o));
  EXPECT_FALSE(isLeaving(0.5, o));
  // Hysteresis: once leaving, until at least in_view_again_fraction is in view.
  EXPECT_TRUE(isLeaving(0.55, o, true));
  EXPECT_FALSE(isLeaving(0.6, o, true));
  o.in_view_again_fraction = 0.3;  // never below leaving_fraction
  EXPECT_TRUE(isLeaving(0.45, o, true));
  o.leaving_fraction = 0.0;  // off (the paper)
  EXPECT_FALSE(isLeaving(0.0, o));
  EXPECT_FALSE(isLeaving(0.0, o, true));
}

TEST(ObjectRules, GrowthInWholeBlocks) {
  // 8 x 8 x 8 blocks of 8 voxels of 1 cm: the volume spans [0, 0.64) m per axis.
  const Eigen::Vector3i dims(8, 8, 8);
  std::vector<Eigen::Vector3d> pts = {{0.1, 0.1, 0.1}, {0.63, 0.5, 0.5}};
  EXPECT_FALSE(planGrowth(pts, dims, 0.01, 8, 4).any());
  pts.push_back({-0.01, 0.5, 0.70});      // 1 cm below x: 1 block; 6 cm above z: 1 block
  pts.push_back({0.5, 0.5 + 0.64, 0.5});  // 0.50 m beyond y: 7 blocks, capped at 4
  const GrowPlan g = planGrowth(pts, dims, 0.01, 8, 4);
  EXPECT_EQ(g.add_low, Eigen::Vector3i(1, 0, 0));
  EXPECT_EQ(g.add_high, Eigen::Vector3i(0, 4, 1));
}

}  // namespace
}  // namespace emf::em
