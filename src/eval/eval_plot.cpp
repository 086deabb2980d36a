// writeEvalPlot(): the eval.png of `emf eval`, drawn with OpenCV.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/error.h"
#include "eval/eval.h"
#include "io/atomic_output.h"

namespace emf::eval {
namespace {

constexpr int kPanelH = 480;
constexpr int kTopW = 480;
constexpr int kErrW = 720;
constexpr int kMargin = 56;
const cv::Scalar kGtColor(40, 150, 40);   // BGR green
const cv::Scalar kEstColor(40, 40, 220);  // BGR red
const cv::Scalar kGridColor(225, 225, 225);
const cv::Scalar kTextColor(30, 30, 30);

// A "nice" grid step (1, 2 or 5 x 10^k) giving about `ticks` divisions of `range`.
double niceStep(double range, int ticks) {
  if (!(range > 0)) return 1.0;
  const double raw = range / ticks;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * p >= raw) return m * p;
  }
  return 10 * p;
}

void text(cv::Mat& img, const std::string& s, cv::Point at, double scale = 0.42) {
  cv::putText(img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, kTextColor, 1, cv::LINE_AA);
}

std::string num(double v, double step) {
  char buf[32];
  const int decimals = std::max(0, static_cast<int>(std::ceil(-std::log10(step) - 1e-9)));
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, v);
  return buf;
}

// A plot area mapping data (x, y) to pixels inside `area` of `img`, with grid and labels.
struct Axes {
  cv::Rect area;
  double x0, x1, y0, y1;
  cv::Point map(double x, double y) const {
    const double u = area.x + (x - x0) / (x1 - x0) * area.width;
    const double v = area.y + area.height - (y - y0) / (y1 - y0) * area.height;
    return {static_cast<int>(std::lround(u)), static_cast<int>(std::lround(v))};
  }
  void draw(cv::Mat& img, const std::string& xlabel, const std::string& ylabel) const {
    const double sx = niceStep(x1 - x0, 6), sy = niceStep(y1 - y0, 6);
    for (double x = std::ceil(x0 / sx) * sx; x <= x1 + 1e-12; x += sx) {
      cv::line(img, map(x, y0), map(x, y1), kGridColor, 1);
      text(img, num(x, sx), map(x, y0) + cv::Point(-12, 16), 0.38);
    }
    for (double y = std::ceil(y0 / sy) * sy; y <= y1 + 1e-12; y += sy) {
      cv::line(img, map(x0, y), map(x1, y), kGridColor, 1);
      text(img, num(y, sy), map(x0, y) + cv::Point(-50, 4), 0.38);
    }
    cv::rectangle(img, area, cv::Scalar(120, 120, 120), 1);
    text(img, xlabel, cv::Point(area.x + area.width / 2 - 20, area.y + area.height + 36));
    text(img, ylabel, cv::Point(area.x - 50, area.y - 16));
  }
};

void polyline(cv::Mat& img, const Axes& ax, const std::vector<cv::Point2d>& pts,
              const cv::Scalar& color) {
  std::vector<cv::Point> px;
  for (const auto& p : pts) px.push_back(ax.map(p.x, p.y));
  if (px.size() >= 2) cv::polylines(img, px, false, color, 1, cv::LINE_AA);
  for (const auto& p : px) cv::circle(img, p, 1, color, -1, cv::LINE_AA);
}

cv::Mat drawRow(const TrajectoryEval& e) {
  cv::Mat img(kPanelH, kTopW + kErrW, CV_8UC3, cv::Scalar(255, 255, 255));
  const AteResult& ate = *e.ate;
  // Top view: look along the axis in which the ground truth extends least.
  Eigen::Vector3d lo = ate.gt_positions[0], hi = lo;
  for (const auto& p : ate.gt_positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  int view_axis = 0;
  (hi - lo).minCoeff(&view_axis);
  const int ax_u = view_axis == 0 ? 1 : 0, ax_v = view_axis == 2 ? 1 : 2;
  std::vector<cv::Point2d> gt, est;
  double u0 = 1e300, u1 = -1e300, v0 = 1e300, v1 = -1e300;
  for (size_t k = 0; k < ate.gt_positions.size(); ++k) {
    gt.emplace_back(ate.gt_positions[k][ax_u], ate.gt_positions[k][ax_v]);
    est.emplace_back(ate.est_positions_aligned[k][ax_u], ate.est_positions_aligned[k][ax_v]);
    for (const auto& p : {gt.back(), est.back()}) {
      u0 = std::min(u0, p.x);
      u1 = std::max(u1, p.x);
      v0 = std::min(v0, p.y);
      v1 = std::max(v1, p.y);
    }
  }
  // Equal scale on both axes, square panel, 5% padding.
  const double half = 0.55 * std::max({u1 - u0, v1 - v0, 1e-3});
  const double cu = 0.5 * (u0 + u1), cv_ = 0.5 * (v0 + v1);
  const cv::Rect top_area(kMargin + 10, 50, kTopW - kMargin - 30, kPanelH - 100);
  const int side = std::min(top_area.width, top_area.height);
  Axes top{cv::Rect(top_area.x, top_area.y, side, side), cu - half, cu + half, cv_ - half,
           cv_ + half};
  static const char* kAxisNames[3] = {"x", "y", "z"};
  top.draw(img, std::string(kAxisNames[ax_u]) + " [m]", std::string(kAxisNames[ax_v]) + " [m]");
  polyline(img, top, gt, kGtColor);
  polyline(img, top, est, kEstColor);
  text(img, e.name + ": top view (along " + kAxisNames[view_axis] + ")", cv::Point(10, 18), 0.5);
  cv::putText(img, "ground truth", cv::Point(top.area.x + 8, top.area.y + 16),
              cv::FONT_HERSHEY_SIMPLEX, 0.42, kGtColor, 1, cv::LINE_AA);
  cv::putText(img, "aligned estimate", cv::Point(top.area.x + 8, top.area.y + 32),
              cv::FONT_HERSHEY_SIMPLEX, 0.42, kEstColor, 1, cv::LINE_AA);

  // Translational error over time.
  const double t0 = ate.gt_stamps.front();
  const double t1 = std::max(ate.gt_stamps.back(), t0 + 1e-3);
  const double emax = std::max(ate.trans_m.max * 1.1, 1e-6);
  Axes err{cv::Rect(kTopW + kMargin, 50, kErrW - kMargin - 24, kPanelH - 110), 0.0, t1 - t0, 0.0,
           emax};
  err.draw(img, "time [s]", "error [m]");
  std::vector<cv::Point2d> curve;
  for (size_t k = 0; k < ate.errors_m.size(); ++k) {
    curve.emplace_back(ate.gt_stamps[k] - t0, ate.errors_m[k]);
  }
  polyline(img, err, curve, kEstColor);
  cv::line(img, err.map(0, ate.trans_m.rmse), err.map(t1 - t0, ate.trans_m.rmse),
           cv::Scalar(160, 90, 0), 1, cv::LINE_AA);
  char title[200];
  std::snprintf(title, sizeof(title), "ATE: %zu pairs, RMSE %.4f m (blue line), max %.4f m",
                ate.pairs, ate.trans_m.rmse, ate.trans_m.max);
  text(img, title, cv::Point(kTopW + 10, 18), 0.5);
  return img;
}

}  // namespace

void writeEvalPlot(const std::string& path, const EvalReport& report) {
  std::vector<cv::Mat> rows;
  if (report.camera.ate) rows.push_back(drawRow(report.camera));
  for (const auto& o : report.objects) {
    if (o.eval.ate) rows.push_back(drawRow(o.eval));
  }
  if (rows.empty()) throw InvalidArgument("writeEvalPlot: nothing to draw (no ATE results)");
  cv::Mat img;
  cv::vconcat(rows, img);
  std::vector<unsigned char> png;
  if (!cv::imencode(".png", img, png)) throw IoError("cannot encode the plot '" + path + "'");
  io::writeFileAtomically(path, std::string(png.begin(), png.end()));
}

}  // namespace emf::eval
