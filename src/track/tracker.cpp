#include "track/tracker.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "common/error.h"

namespace emf::track {
namespace {

// Must match kernels_cl/track_reduce.cl.
constexpr int kTerms = 36;
// Work-group shape of track_accumulate (2D over the sampled grid, each work item takes 16
// consecutive sampled columns of one row): 2 x 8 items = 32 sampled columns x 8 rows.
constexpr int kLanes = 16;  // TRACK_COLS, whatever the kernels' lane width
constexpr int kLocalX = 2;
constexpr int kLocalY = 8;
constexpr int kLocalSize = kLocalX * kLocalY;
constexpr double kPi = 3.14159265358979323846;
// Recovery after a lost call asks for at most the volume's typical inlier ratio minus this
// margin (noisy sensors: good synthetic Kinect-v1 frames at 1 cm voxels reach only ~0.85), and
// the typical ratio follows the tracked calls at this rate.
constexpr double kRecoveryMargin = 0.05;
constexpr double kTypicalRate = 0.1;
// Relative damping of the Gauss-Newton step that the early exit measures.
constexpr double kGaussNewtonDamping = 1e-6;

enum Term : int {
  kH = 0,
  kG = 21,
  kCost = 27,
  kValid = 28,
  kInliers = 29,
  kInput = 30,
  kMaxWeight = 31,
  kCostChange = 32,
  kCommon = 33,
  kStrictInliers = 34,
  kValidWeight = 35,
};

void unpackTerms(const double* t, NormalEquations* ne) {
  int k = 0;
  for (int a = 0; a < 6; ++a) {
    for (int b = a; b < 6; ++b) {
      ne->H(a, b) = t[k];
      ne->H(b, a) = t[k];
      ++k;
    }
  }
  for (int a = 0; a < 6; ++a) ne->g(a) = t[kG + a];
  ne->cost = t[kCost];
  ne->valid = static_cast<int>(std::lround(t[kValid]));
  ne->inliers = t[kInliers];
  ne->input = static_cast<int>(std::lround(t[kInput]));
  ne->max_weight = t[kMaxWeight];
  ne->cost_change = t[kCostChange];
  ne->common = static_cast<int>(std::lround(t[kCommon]));
  ne->strict_inliers = t[kStrictInliers];
  ne->valid_weight = t[kValidWeight];
}

void checkVolume(const map::VolumeDeviceView& v) {
  if (!v.index || !v.voxels || (v.dims_blocks.array() <= 0).any() || !(v.voxel_size_m > 0.f) ||
      !(v.truncation_m > 0.f)) {
    std::ostringstream s;
    s << "tracking: invalid volume view (index " << v.index << ", voxels " << v.voxels << ", dims "
      << v.dims_blocks.transpose() << " blocks, voxel " << v.voxel_size_m << " m, truncation "
      << v.truncation_m << " m): pass a volume created by the map with buffers, dims and sizes set";
    throw InvalidArgument(s.str());
  }
}

}  // namespace

const char* trackLossName(TrackLoss loss) {
  switch (loss) {
    case TrackLoss::kNone:
      return "none";
    case TrackLoss::kNoDepth:
      return "no_depth";
    case TrackLoss::kFewValidPoints:
      return "few_valid_points";
    case TrackLoss::kLargeMotion:
      return "large_motion";
    case TrackLoss::kFewInliers:
      return "few_inliers";
    case TrackLoss::kDegenerate:
      return "degenerate";
    case TrackLoss::kNotConverged:
      return "not_converged";
  }
  return "unknown";
}

NormalEquations accumulateReference(const map::VolumeHostView& volume, const cv::Mat& vertex,
                                    const cv::Mat& q, int stride,
                                    const Eigen::Isometry3d& T_volume_camera, double huber_delta_m,
                                    const cv::Mat* prev_cost, cv::Mat* pixel_cost,
                                    double inlier_noise_per_m2, bool fixed_weights,
                                    double inlier_delta_m) {
  if (vertex.type() != CV_32FC4 || (!q.empty() && (q.type() != CV_32F || q.size != vertex.size))) {
    throw InvalidArgument(
        "accumulateReference: vertex must be CV_32FC4 and q empty or CV_32F of the same size");
  }
  if (stride < 1) throw InvalidArgument("accumulateReference: stride must be >= 1");
  if (prev_cost && (prev_cost->type() != CV_32FC2 || prev_cost->size != vertex.size)) {
    throw InvalidArgument("accumulateReference: prev_cost must be CV_32FC2 of the vertex size");
  }
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  if (pixel_cost && (pixel_cost->type() != CV_32FC2 || pixel_cost->size != vertex.size)) {
    pixel_cost->create(vertex.rows, vertex.cols, CV_32FC2);
    pixel_cost->setTo(cv::Scalar(kNaN, kNaN));
  }
  double t[kTerms] = {};
  const Eigen::Matrix4f M = T_volume_camera.matrix().cast<float>();
  const double delta = static_cast<float>(huber_delta_m);
  const float inlier_delta =
      static_cast<float>(inlier_delta_m < 0.0 ? huber_delta_m : inlier_delta_m);
  for (int v = 0; v < vertex.rows; v += stride) {
    for (int u = 0; u < vertex.cols; u += stride) {
      const cv::Vec4f p = vertex.at<cv::Vec4f>(v, u);
      const float qu = q.empty() ? 1.0f : q.at<float>(v, u);
      if (pixel_cost) pixel_cost->at<cv::Vec2f>(v, u) = {kNaN, 0.0f};
      if (!(p[3] > 0.0f) || !(qu > 0.0f)) continue;
      t[kInput] += 1.0;
      // Same float transform as the kernel, so both sample the SDF at the same point.
      const Eigen::Vector3f xf =
          M.topLeftCorner<3, 3>() * Eigen::Vector3f(p[0], p[1], p[2]) + M.topRightCorner<3, 1>();
      float psi, weight;
      Eigen::Vector3f grad;
      if (!map::sampleSdfReference(volume, xf, &psi, &weight, &grad)) continue;
      t[kValid] += 1.0;
      const double r = psi, abs_r = std::abs(r);
      const bool inlier = abs_r <= delta;
      const double c = static_cast<double>(qu) * weight;
      const float inlier_radius = std::max(
          inlier_delta, static_cast<float>(inlier_noise_per_m2) * p[2] * p[2]);  // as the kernel
      t[kInliers] += abs_r <= inlier_radius ? qu : 0.0;
      t[kStrictInliers] += abs_r <= inlier_delta ? qu : 0.0;
      t[kValidWeight] += qu;
      const double rho = inlier ? 0.5 * r * r : delta * (abs_r - 0.5 * delta);
      const double cost = c * rho;
      t[kCost] += cost;
      if (pixel_cost)
        pixel_cost->at<cv::Vec2f>(v, u) = {static_cast<float>(cost), static_cast<float>(c)};
      if (prev_cost && !std::isnan(prev_cost->at<cv::Vec2f>(v, u)[0])) {
        const cv::Vec2f prev = prev_cost->at<cv::Vec2f>(v, u);
        const double now = fixed_weights ? static_cast<double>(prev[1]) * rho : cost;
        t[kCostChange] += now - prev[0];
        t[kCommon] += 1.0;
      }
      const double wt = c * (inlier ? 1.0 : delta / abs_r);
      const Eigen::Vector3d gd = grad.cast<double>();
      const Eigen::Vector3d jr = xf.cast<double>().cross(gd);
      const double j[6] = {gd.x(), gd.y(), gd.z(), jr.x(), jr.y(), jr.z()};
      int k = 0;
      for (int a = 0; a < 6; ++a) {
        for (int b = a; b < 6; ++b) t[k++] += wt * j[a] * j[b];
        t[kG + a] += wt * j[a] * r;
      }
      t[kMaxWeight] = std::max(t[kMaxWeight], static_cast<double>(weight));
    }
  }
  NormalEquations ne;
  unpackTerms(t, &ne);
  return ne;
}

Eigen::Vector3d stiffnessCentre(const Matrix6d& H) {
  // Increments about a centre c: J' = (g, (x - c) x g) = M J with M = [[I, 0], [-[c]x, I]], so
  // the coupling block of M H M^T is H_rt - [c]x H_tt. Its least-squares zero: for every
  // column h_k of H_tt, c x h_k = (H_rt)_k, i.e. -[h_k]x c = (H_rt)_k (9 equations). For
  // constraints spread evenly over the points this is their weighted centroid; along
  // directions the translation block does not constrain, a small ridge keeps c at the origin.
  Eigen::Matrix3d AtA = Eigen::Matrix3d::Zero();
  Eigen::Vector3d Atb = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) {
    const Eigen::Matrix3d A = -hat(H.block<3, 1>(0, k));
    AtA += A.transpose() * A;
    Atb += A.transpose() * H.block<3, 1>(3, k);
  }
  const double ridge = 1e-9 * AtA.trace();
  if (!(ridge > 0.0) || !std::isfinite(ridge)) return Eigen::Vector3d::Zero();
  const Eigen::Vector3d c = (AtA + ridge * Eigen::Matrix3d::Identity()).ldlt().solve(Atb);
  return c.allFinite() ? c : Eigen::Vector3d::Zero();
}

Matrix6d centringMap(const Eigen::Vector3d& c) {
  Matrix6d M = Matrix6d::Identity();
  M.bottomLeftCorner<3, 3>() = -hat(c);
  return M;
}

double balancedInverseCondition(const Matrix6d& H_origin) {
  const Matrix6d M = centringMap(stiffnessCentre(H_origin));
  const Matrix6d H = M * H_origin * M.transpose();
  const double tt = H.topLeftCorner<3, 3>().trace();
  const double rr = H.bottomRightCorner<3, 3>().trace();
  if (!(tt > 0.0) || !(rr > 0.0) || !H.allFinite()) return 0.0;
  Vector6d s;
  s << 1.0, 1.0, 1.0, Eigen::Vector3d::Constant(std::sqrt(tt / rr));
  const Matrix6d Hs = s.asDiagonal() * H * s.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Matrix6d> es(Hs, Eigen::EigenvaluesOnly);
  const double lmax = es.eigenvalues().maxCoeff();
  if (!(lmax > 0.0)) return 0.0;
  return std::max(0.0, es.eigenvalues().minCoeff()) / lmax;
}

Tracker::Tracker(cl::Context& ctx, const TrackOptions& options, int width, int height)
    : ctx_(ctx), options_(options), width_(width), height_(height) {
  options_.pixel_stride = options.pixelStrideFor(width);
  if (width <= 0 || height <= 0) {
    std::ostringstream s;
    s << "tracking: image size " << width << "x" << height << " is invalid";
    throw InvalidArgument(s.str());
  }
  const std::string defs =
      "-DTRACK_LX=" + std::to_string(kLocalX) + " -DTRACK_LY=" + std::to_string(kLocalY);
  accumulate_ = ctx_.kernel("track_reduce", "track_accumulate", defs);
  reduce_ = ctx_.kernel("track_reduce", "track_reduce_partials", defs);
  cl_ulong device_local = 0;
  EMF_CL_CHECK(clGetDeviceInfo(ctx_.deviceId(), CL_DEVICE_LOCAL_MEM_SIZE, sizeof(device_local),
                               &device_local, nullptr));
  if (kernelLocalMemoryBytes() > device_local) {
    std::ostringstream s;
    s << "tracking: the accumulation kernel needs " << kernelLocalMemoryBytes()
      << " bytes of local memory per work-group, the device '" << ctx_.device().device_name
      << "' offers " << device_local << "; choose another device (emf devices)";
    throw ResourceError(s.str());
  }
  const int max_groups = numGroups(1);
  partials_ = ctx_.buffer(CL_MEM_READ_WRITE, sizeof(float) * kTerms * max_groups);
  reduced_ = ctx_.buffer(CL_MEM_READ_WRITE, sizeof(float) * kTerms);
  const std::vector<float> ones(static_cast<size_t>(width) * height, 1.0f);
  ones_ = ctx_.buffer(CL_MEM_READ_ONLY, ones.size() * sizeof(float), ones.data());
  for (int i = 0; i < 2; ++i) {
    costs_[i] = ctx_.buffer(CL_MEM_READ_WRITE, ones.size() * sizeof(float));
    weights_[i] = ctx_.buffer(CL_MEM_READ_WRITE, ones.size() * sizeof(float));
  }
  host_partials_.resize(static_cast<size_t>(kTerms) * max_groups);
}

int Tracker::localSize() { return kLocalSize; }

size_t Tracker::kernelLocalMemoryBytes() const {
  cl_ulong bytes = 0;
  EMF_CL_CHECK(clGetKernelWorkGroupInfo(accumulate_.get(), ctx_.deviceId(),
                                        CL_KERNEL_LOCAL_MEM_SIZE, sizeof(bytes), &bytes, nullptr));
  return static_cast<size_t>(bytes);
}

PixelRect volumeImageBounds(const Eigen::Vector3d& extent_m,
                            const Eigen::Isometry3d& T_volume_camera, const core::Intrinsics& k) {
  return boxImageBounds(Eigen::AlignedBox3d(Eigen::Vector3d::Zero(), extent_m), T_volume_camera, k);
}

PixelRect boxImageBounds(const Eigen::AlignedBox3d& box, const Eigen::Isometry3d& T_volume_camera,
                         const core::Intrinsics& k) {
  if (box.isEmpty()) return PixelRect{};
  const PixelRect whole{0, 0, k.width, k.height};
  const Eigen::Isometry3d T_camera_volume = T_volume_camera.inverse();
  double u_min = std::numeric_limits<double>::infinity(), u_max = -u_min;
  double v_min = u_min, v_max = -u_min;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d p =
        T_camera_volume * box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c));
    if (!(p.z() > 1e-3)) return whole;  // behind or at the camera: no bounded projection
    const double u = k.fx * p.x() / p.z() + k.cx;
    const double v = k.fy * p.y() / p.z() + k.cy;
    u_min = std::min(u_min, u);
    u_max = std::max(u_max, u);
    v_min = std::min(v_min, v);
    v_max = std::max(v_max, v);
  }
  // The box is convex and in front of the camera: its projection is the hull of its corners'.
  auto clampTo = [](double x, int hi) {
    return static_cast<int>(std::max(0.0, std::min(static_cast<double>(hi), x)));
  };
  PixelRect r;
  r.x0 = clampTo(std::floor(u_min) - 1.0, k.width);
  r.y0 = clampTo(std::floor(v_min) - 1.0, k.height);
  r.x1 = clampTo(std::ceil(u_max) + 2.0, k.width);
  r.y1 = clampTo(std::ceil(v_max) + 2.0, k.height);
  return r;
}

Tracker::GridRange Tracker::gridRange(int stride, const PixelRect* roi,
                                      const PixelRect* inputs) const {
  GridRange g;
  g.su1 = (width_ + stride - 1) / stride;
  g.sv1 = (height_ + stride - 1) / stride;
  if (roi) {
    // Sampled pixel u = su * stride lies in [x0, x1) <=> ceil(x0 / s) <= su < ceil(x1 / s).
    auto cell = [stride](int x) { return (std::max(0, x) + stride - 1) / stride; };
    g.su0 = std::min(g.su1, cell(roi->x0));
    g.sv0 = std::min(g.sv1, cell(roi->y0));
    g.su1 = std::max(g.su0, std::min(g.su1, cell(roi->x1)));
    g.sv1 = std::max(g.sv0, std::min(g.sv1, cell(roi->y1)));
  }
  if (inputs) {
    // The work-groups (kLanes * kLocalX cells by kLocalY rows, counted from su0, sv0) that meet
    // the inputs' cells; the groups kept hold the same pixels as before.
    const GridRange in = gridRange(stride, inputs, nullptr);
    const int u0 = std::max(in.su0, g.su0), u1 = std::min(in.su1, g.su1);
    const int v0 = std::max(in.sv0, g.sv0), v1 = std::min(in.sv1, g.sv1);
    if (u0 >= u1 || v0 >= v1) return GridRange{g.su0, g.sv0, g.su0, g.sv0};
    constexpr int kGroupCols = kLanes * kLocalX, kGroupRows = kLocalY;
    const auto groupsUpTo = [](int cells, int per) { return (cells + per - 1) / per * per; };
    g.su1 = std::min(g.su1, g.su0 + groupsUpTo(u1 - g.su0, kGroupCols));
    g.sv1 = std::min(g.sv1, g.sv0 + groupsUpTo(v1 - g.sv0, kGroupRows));
    g.su0 += (u0 - g.su0) / kGroupCols * kGroupCols;
    g.sv0 += (v0 - g.sv0) / kGroupRows * kGroupRows;
  }
  return g;
}

int Tracker::numGroups(int stride, const PixelRect* roi, const PixelRect* inputs) const {
  const GridRange g = gridRange(stride, roi, inputs);
  const int items_x = (g.su1 - g.su0 + kLanes - 1) / kLanes;
  return ((items_x + kLocalX - 1) / kLocalX) * ((g.sv1 - g.sv0 + kLocalY - 1) / kLocalY);
}

NormalEquations Tracker::evaluate(const map::VolumeDeviceView& volume, cl_mem vertex_map, cl_mem q,
                                  const Eigen::Isometry3d& T_volume_camera, int stride,
                                  bool compare_with_last, const PixelRect* roi,
                                  const PixelRect* inputs) {
  const NormalEquations ne = evaluateCandidate(volume, vertex_map, q, T_volume_camera, stride,
                                               compare_with_last, roi, inputs);
  current_ = 1 - current_;
  return ne;
}

cv::Mat Tracker::lastPixelCosts() const {
  cv::Mat cost(height_, width_, CV_32F), weight(height_, width_, CV_32F, cv::Scalar(0));
  ctx_.read(costs_[current_], cost.ptr<float>(0), cost.total() * sizeof(float));
  if (options_.step_acceptance == StepAcceptance::kFixedWeights) {
    ctx_.read(weights_[current_], weight.ptr<float>(0), weight.total() * sizeof(float));
  }
  cv::Mat out;
  cv::merge(std::vector<cv::Mat>{cost, weight}, out);
  return out;
}

NormalEquations Tracker::evaluateCandidate(const map::VolumeDeviceView& volume, cl_mem vertex_map,
                                           cl_mem q, const Eigen::Isometry3d& T_volume_camera,
                                           int stride, bool compare, const PixelRect* roi,
                                           const PixelRect* inputs) {
  checkVolume(volume);
  if (!vertex_map) throw InvalidArgument("tracking: vertex map buffer is null");
  if (stride < 1) throw InvalidArgument("tracking: pixel stride must be >= 1");
  const GridRange grid = gridRange(stride, roi, inputs);
  const int groups = numGroups(stride, roi, inputs);
  if (groups == 0) return NormalEquations();  // an empty rectangle: no pixel, no terms
  const Eigen::Matrix4f M = T_volume_camera.matrix().cast<float>();
  cl_float4 rows[3];
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) rows[r].s[c] = M(r, c);
  }
  cl_int4 dims;
  dims.s[0] = volume.dims_blocks.x();
  dims.s[1] = volume.dims_blocks.y();
  dims.s[2] = volume.dims_blocks.z();
  dims.s[3] = 0;
  const float delta = static_cast<float>(options_.huber_truncation_factor * volume.truncation_m);
  const float inlier_delta =
      static_cast<float>(options_.inlier_truncation_factor * volume.truncation_m);
  cl::setArgs(accumulate_, vertex_map, q ? q : ones_.get(), width_, height_, stride,
              static_cast<cl_int>(grid.su0), static_cast<cl_int>(grid.sv0),
              static_cast<cl_int>(grid.su1), static_cast<cl_int>(grid.sv1), rows[0], rows[1],
              rows[2], volume.index, dims, volume.voxels, volume.voxel_size_m, volume.truncation_m,
              delta, inlier_delta, static_cast<cl_float>(options_.inlier_noise_per_m2),
              costs_[current_].get(), costs_[1 - current_].get(), weights_[current_].get(),
              weights_[1 - current_].get(), compare ? 1 : 0,
              static_cast<cl_int>(options_.step_acceptance == StepAcceptance::kFixedWeights),
              partials_.get());
  cl::enqueue(ctx_.queue(), accumulate_,
              static_cast<size_t>((grid.su1 - grid.su0 + kLanes - 1) / kLanes),
              static_cast<size_t>(grid.sv1 - grid.sv0), 0, kLocalX, kLocalY);
  double t[kTerms] = {};
  if (options_.final_reduction == FinalReduction::kDevice) {
    cl::setArgs(reduce_, partials_.get(), groups, reduced_.get());
    cl::enqueue(ctx_.queue(), reduce_, kTerms);
    float out[kTerms];
    ctx_.read(reduced_, out, sizeof(out));
    for (int k = 0; k < kTerms; ++k) t[k] = out[k];
  } else {
    ctx_.read(partials_, host_partials_.data(), sizeof(float) * kTerms * groups);
    for (int gi = 0; gi < groups; ++gi) {
      const float* row = host_partials_.data() + static_cast<size_t>(gi) * kTerms;
      for (int k = 0; k < kTerms; ++k) {
        t[k] = k == kMaxWeight ? std::max(t[k], static_cast<double>(row[k])) : t[k] + row[k];
      }
    }
  }
  NormalEquations ne;
  unpackTerms(t, &ne);
  return ne;
}

Tracker::LevelResult Tracker::runLevel(const map::VolumeDeviceView& volume, cl_mem vertex_map,
                                       cl_mem q, int stride, int max_iterations, double tau,
                                       double inv_max_weight, Eigen::Isometry3d* T,
                                       NormalEquations* at_T, const PixelRect* roi,
                                       const PixelRect* inputs, const Eigen::Isometry3d& T_prior,
                                       double prior_scale) {
  // Levenberg-Marquardt (Madsen, Nielsen & Tingleff, "Methods for non-linear least squares
  // problems", 2004, alg. 3.16) on left increments; all terms scaled by 1 / max W. The actual
  // cost reduction of a step is measured over the pixels valid at both poses.
  LevelResult res;
  const double eps = options_.lm_eps;
  // The volume's left increments rotate about the volume origin, which can lie metres from
  // the points (a 5 m background seen from one face): rotation and translation then couple
  // strongly, and the damping and step sizes depend on where the origin happens to be (a 7.7 m
  // background lost most of redkitchen as degenerate). LM runs on increments h' about the
  // centre chosen by track.rotation_centre at the start of the level instead (H' = M H M^T,
  // g' = M g, volume increment h = M^T h'); step sizes below are those of h'.
  const Matrix6d M = options_.rotation_centre == RotationCentre::kOrigin ? Matrix6d::Identity()
                     : options_.rotation_centre == RotationCentre::kStiffness
                         ? centringMap(stiffnessCentre(at_T->H))
                         : centringMap(T->translation());
  // Motion prior (prior_*_weight): E_p = d' Lambda d' / 2, d' the pose's left difference from
  // T_prior in the centred increments (d' = M^-T d), Lambda diagonal.
  Vector6d lambda;
  lambda << Eigen::Vector3d::Constant(options_.prior_translation_weight * prior_scale),
      Eigen::Vector3d::Constant(options_.prior_rotation_weight * prior_scale);
  const bool with_prior = lambda.maxCoeff() > 0.0;
  const Matrix6d M_inv_T = M.inverse().transpose();
  const auto priorDeviation = [&](const Eigen::Isometry3d& T_now) {
    const Eigen::Matrix3d R_d = T_now.linear() * T_prior.linear().transpose();
    Vector6d d;
    d << T_now.translation() - R_d * T_prior.translation(), logSo3(R_d);
    return Vector6d(M_inv_T * d);
  };
  Vector6d dev = with_prior ? priorDeviation(*T) : Vector6d::Zero();
  const auto priorCost = [&](const Vector6d& d) { return 0.5 * d.dot(lambda.cwiseProduct(d)); };
  Matrix6d H = M * at_T->H * M.transpose() * inv_max_weight;
  Vector6d g = M * at_T->g * inv_max_weight;
  H.diagonal() += lambda;
  g += lambda.cwiseProduct(dev);
  double mu = tau * H.diagonal().maxCoeff();
  double nu = options_.lm_nu;
  res.final_damping = tau;
  if (!(mu > 0.0) || !std::isfinite(mu)) return res;  // no gradient information at all
  // Step extrapolation (max_step_scale > 1): where the cost falls much faster than the model
  // predicts (Huber outliers and truncated points make the IRLS Hessian too stiff far from the
  // minimum), the LM step is scaled by up to max_step_scale, doubling per such step; any
  // disappointing or rejected extrapolated step falls back to the plain LM step.
  double scale = 1.0;
  bool new_model = true;  // H and g changed since the early exit last looked at them
  while (res.iterations < max_iterations) {
    if (g.cwiseAbs().maxCoeff() <= eps) {
      res.converged = true;
      break;
    }
    // Early exit: the Gauss-Newton step, the model's distance to its minimum, is below
    // early_exit_step (damped by kGaussNewtonDamping of the largest curvature only, so that a
    // degenerate direction gives a long step, not a NaN). Testing the damped LM step instead
    // ended levels while LM was still ramping its damping down from lm_tau = 1e3, with steps of
    // 1e-7 growing 3x per iteration: the first frames of a run stayed at their prediction, up to
    // 3.6 cm off on noise-free cars frames (a stall rule for crawling steps fired in that ramp
    // too).
    if (options_.early_exit_step > 0.0 && new_model) {
      new_model = false;
      const double damping = kGaussNewtonDamping * H.diagonal().maxCoeff();
      const Vector6d h_gn = (H + damping * Matrix6d::Identity()).ldlt().solve(-g);
      if (h_gn.allFinite() && h_gn.norm() < options_.early_exit_step) {
        res.converged = true;
        break;
      }
    }
    const Vector6d h_lm = (H + mu * Matrix6d::Identity()).ldlt().solve(-g);
    if (!h_lm.allFinite()) break;
    if (h_lm.norm() <= eps) {
      res.converged = true;
      break;
    }
    const Vector6d h = scale * h_lm;
    const Eigen::Isometry3d T_new = applyLeftIncrement(M.transpose() * h, *T);
    const NormalEquations ne =
        evaluateCandidate(volume, vertex_map, q, T_new, stride, true, roi, inputs);
    ++res.iterations;
    const Vector6d dev_new = with_prior ? priorDeviation(T_new) : Vector6d::Zero();
    const double actual = -ne.cost_change * inv_max_weight + priorCost(dev) - priorCost(dev_new);
    const double predicted = 0.5 * h_lm.dot(mu * h_lm - g);  // model decrease of the LM step
    const double gain = actual / predicted / scale;
    const bool accepted = ne.valid > 0 && predicted > 0.0 && gain > 0.0;
    if (accepted) {
      *T = T_new;
      *at_T = ne;
      current_ = 1 - current_;
      H = M * ne.H * M.transpose() * inv_max_weight;
      g = M * ne.g * inv_max_weight;
      dev = dev_new;
      H.diagonal() += lambda;
      g += lambda.cwiseProduct(dev);
      new_model = true;
      const double c = 2.0 * gain - 1.0;
      mu *= std::max(1.0 / 3.0, 1.0 - c * c * c);
      nu = options_.lm_nu;
      scale =
          gain > 1.5 ? std::min(2.0 * scale, options_.max_step_scale) : (gain < 0.75 ? 1.0 : scale);
    } else if (scale > 1.0) {
      scale = 1.0;  // retry the plain LM step with the same damping
    } else {
      mu *= nu;
      nu *= 2.0;
      if (!std::isfinite(mu)) break;
    }
  }
  const double max_diag = H.diagonal().maxCoeff();
  if (max_diag > 0.0) res.final_damping = mu / max_diag;
  return res;
}

TrackResult Tracker::track(const map::VolumeDeviceView& volume, cl_mem vertex_map, cl_mem q,
                           const Eigen::Isometry3d& T_volume_camera_init, const PixelRect* roi,
                           const PixelRect* inputs) {
  TrackResult result;
  result.T_volume_camera = T_volume_camera_init;
  Eigen::Isometry3d T = T_volume_camera_init;
  const int levels = options_.coarse_levels;
  NormalEquations ne =
      evaluate(volume, vertex_map, q, T, options_.pixel_stride << levels, false, roi, inputs);
  double inv_max_weight = 0.0;
  if (ne.max_weight > 0.0) inv_max_weight = 1.0 / ne.max_weight;
  bool finest_converged = false;
  double tau = options_.lm_tau;
  for (int level = levels; level >= 0 && inv_max_weight > 0.0; --level) {
    const int stride = options_.pixel_stride << level;
    if (level != levels) ne = evaluate(volume, vertex_map, q, T, stride, false, roi, inputs);
    const int cap = level == 0 ? options_.max_iterations : options_.coarse_max_iterations;
    const LevelResult lr =
        runLevel(volume, vertex_map, q, stride, cap, tau, inv_max_weight, &T, &ne, roi, inputs,
                 T_volume_camera_init, 1.0 / static_cast<double>(1 << (2 * level)));
    result.iterations += lr.iterations;
    finest_converged = lr.converged;
    // Later levels continue with the damping reached so far (relative to the curvature)
    // instead of ramping down from lm_tau again.
    tau = std::min(options_.lm_tau, lr.final_damping);
  }
  result.converged = finest_converged;
  result.T_volume_camera = T;
  result.cost = ne.cost * inv_max_weight;
  result.valid_pixels = ne.valid;
  result.input_pixels = ne.input;
  result.cost_per_valid = ne.valid > 0 ? result.cost / ne.valid : 0.0;
  result.valid_fraction = ne.input > 0 ? static_cast<double>(ne.valid) / ne.input : 0.0;
  result.inlier_ratio = ne.valid_weight > 0.0 ? ne.inliers / ne.valid_weight : 0.0;
  result.strict_inlier_ratio = ne.valid_weight > 0.0 ? ne.strict_inliers / ne.valid_weight : 0.0;
  result.inverse_condition = balancedInverseCondition(ne.H);
  const Eigen::Isometry3d motion = T_volume_camera_init.inverse() * T;
  result.motion_m = motion.translation().norm();
  result.motion_deg = rotationAngle(motion) * 180.0 / kPi;

  std::ostringstream why;
  if (ne.input == 0) {
    result.loss = TrackLoss::kNoDepth;
    why << "no pixel has valid depth (and q > 0)";
  } else if (result.valid_fraction < options_.min_valid_fraction) {
    result.loss = TrackLoss::kFewValidPoints;
    why << "only " << ne.valid << " of " << ne.input << " points (" << result.valid_fraction
        << ") land on the observed map, below track.min_valid_fraction "
        << options_.min_valid_fraction;
  } else if (result.motion_m > options_.max_motion_m ||
             result.motion_deg > options_.max_motion_deg) {
    result.loss = TrackLoss::kLargeMotion;
    why << "the pose moved " << result.motion_m << " m / " << result.motion_deg
        << " deg from its initial value, beyond track.max_motion_m " << options_.max_motion_m
        << " / track.max_motion_deg " << options_.max_motion_deg;
  } else if (result.inlier_ratio < options_.min_inlier_ratio) {
    result.loss = TrackLoss::kFewInliers;
    why << "inlier ratio " << result.inlier_ratio << " (points within the inlier radius, weighted "
        << "by q: " << ne.inliers << " of " << ne.valid_weight << "; " << ne.valid
        << " points on the map) is below track.min_inlier_ratio " << options_.min_inlier_ratio;
  } else if (recovering(volume.volume_key) &&
             (result.motion_m > options_.recovery_max_motion_m ||
              result.motion_deg > options_.recovery_max_motion_deg)) {
    result.loss = TrackLoss::kLargeMotion;
    why << "recovering after a lost frame: the pose moved " << result.motion_m << " m / "
        << result.motion_deg
        << " deg from the last tracked one, beyond track.recovery_max_motion_m "
        << options_.recovery_max_motion_m << " / track.recovery_max_motion_deg "
        << options_.recovery_max_motion_deg << " (no relocalisation)";
  } else if (recovering(volume.volume_key) &&
             result.strict_inlier_ratio < recoveryInlierRatio(volume.volume_key)) {
    result.loss = TrackLoss::kFewInliers;
    why << "recovering after a lost frame: inlier ratio " << result.strict_inlier_ratio
        << " (points within track.inlier_truncation_factor of the truncation, weighted by q: "
        << ne.strict_inliers << " of " << ne.valid_weight << "; " << ne.valid
        << " points on the map) is below " << recoveryInlierRatio(volume.volume_key)
        << " (track.recovery_min_inlier_ratio " << options_.recovery_min_inlier_ratio
        << ", at most the volume's typical inlier ratio - " << kRecoveryMargin << ")";
  } else if (result.inverse_condition < options_.min_inverse_condition) {
    result.loss = TrackLoss::kDegenerate;
    why << "degenerate geometry: inverse condition number " << result.inverse_condition
        << " of the balanced Hessian is below track.min_inverse_condition "
        << options_.min_inverse_condition;
  } else if (options_.lost_if_not_converged && !finest_converged) {
    result.loss = TrackLoss::kNotConverged;
    why << "not converged after track.max_iterations " << options_.max_iterations
        << " iterations (track.lost_if_not_converged)";
  }
  result.lost = result.loss != TrackLoss::kNone;
  result.loss_reason = why.str();
  if (!result.lost) {
    // Running typical (strict) inlier ratio of the volume's tracked calls.
    const auto t = typical_inliers_.find(volume.volume_key);
    if (t == typical_inliers_.end()) {
      typical_inliers_[volume.volume_key] = result.strict_inlier_ratio;
    } else {
      t->second += kTypicalRate * (result.strict_inlier_ratio - t->second);
    }
  }
  const auto it = std::find(lost_volumes_.begin(), lost_volumes_.end(), volume.volume_key);
  if (result.lost && it == lost_volumes_.end()) lost_volumes_.push_back(volume.volume_key);
  if (!result.lost && it != lost_volumes_.end()) lost_volumes_.erase(it);
  return result;
}

double Tracker::recoveryInlierRatio(uint64_t volume_key) const {
  const auto t = typical_inliers_.find(volume_key);
  if (t == typical_inliers_.end()) return options_.recovery_min_inlier_ratio;
  return std::min(options_.recovery_min_inlier_ratio, t->second - kRecoveryMargin);
}

void Tracker::forget(uint64_t volume_key) {
  lost_volumes_.erase(std::remove(lost_volumes_.begin(), lost_volumes_.end(), volume_key),
                      lost_volumes_.end());
  typical_inliers_.erase(volume_key);
}

bool Tracker::recovering(uint64_t volume_key) const {
  return std::find(lost_volumes_.begin(), lost_volumes_.end(), volume_key) != lost_volumes_.end();
}

}  // namespace emf::track
