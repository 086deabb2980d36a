#include "pipeline/run_view.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "common/error.h"

namespace emf::pipeline {
namespace {

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
const cv::Scalar kWhite(255, 255, 255), kGray(140, 140, 140), kRed(60, 60, 255);

// Text scale for a tile `width` pixels wide: readable at 320 and 640.
double textScale(int width) { return std::max(0.35, width / 1400.0); }

void putLabel(cv::Mat& img, const std::string& text, cv::Point at, const cv::Scalar& color,
              double scale) {
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, kFont, scale, 1, &baseline);
  at.x = std::clamp(at.x, 0, std::max(0, img.cols - size.width));
  at.y = std::clamp(at.y, size.height + 2, std::max(size.height + 2, img.rows - baseline));
  cv::rectangle(img, at + cv::Point(-2, baseline), at + cv::Point(size.width + 2, -size.height - 2),
                cv::Scalar(0, 0, 0), cv::FILLED);
  cv::putText(img, text, at, kFont, scale, color, 1, cv::LINE_AA);
}

void putTitle(cv::Mat& tile, const std::string& title) {
  putLabel(tile, title, cv::Point(4, 4), kWhite, textScale(2 * tile.cols));
}

cv::Mat resized(const cv::Mat& img, cv::Size size, int interpolation = cv::INTER_AREA) {
  cv::Mat out;
  cv::resize(img, out, size, 0, 0, interpolation);
  return out;
}

cv::Mat depthFalseColor(const cv::Mat& depth) {
  cv::Mat gray(depth.size(), CV_8U), invalid(depth.size(), CV_8U);
  for (int y = 0; y < depth.rows; ++y) {
    const float* d = depth.ptr<float>(y);
    uint8_t* g = gray.ptr<uint8_t>(y);
    uint8_t* v = invalid.ptr<uint8_t>(y);
    for (int x = 0; x < depth.cols; ++x) {
      const bool ok = std::isfinite(d[x]) && d[x] > 0;
      v[x] = ok ? 0 : 255;
      g[x] = ok ? cv::saturate_cast<uint8_t>(255.0 * d[x] / kViewDepthRangeM) : 0;
    }
  }
  cv::Mat out;
  cv::applyColorMap(gray, out, cv::COLORMAP_JET);
  out.setTo(cv::Scalar(0, 0, 0), invalid);
  return out;
}

std::string stateSuffix(ObjectState s) {
  return s == ObjectState::kTracked ? "" : std::string(" [") + objectStateName(s) + "]";
}

}  // namespace

cv::Mat RunView::overlayTile(const ViewFrame& f) {
  cv::Mat tile = objectOverlay(f.color, f.object_ids);
  const double scale = textScale(tile.cols);
  // Each object's label just above its rendered pixels (not on them: the colour shows through).
  std::map<int, cv::Rect> boxes;
  for (int y = 0; y < f.object_ids.rows; ++y) {
    const int32_t* ids = f.object_ids.ptr<int32_t>(y);
    for (int x = 0; x < f.object_ids.cols; ++x) {
      if (ids[x] <= 0) continue;
      auto it = boxes.find(ids[x]);
      if (it == boxes.end()) {
        boxes.emplace(ids[x], cv::Rect(x, y, 1, 1));
      } else {
        it->second |= cv::Rect(x, y, 1, 1);
      }
    }
  }
  for (const ObjectOutcome& o : f.objects) {
    const auto it = boxes.find(o.id);
    if (it == boxes.end()) continue;
    const cv::Vec3b col = objectColor(o.id);
    putLabel(tile, std::to_string(o.id) + " " + o.class_name + stateSuffix(o.state),
             cv::Point(it->second.x, it->second.y - 3), cv::Scalar(col[0], col[1], col[2]), scale);
  }
  char status[256];
  int alive = 0;
  for (const ObjectOutcome& o : f.objects) alive += o.state != ObjectState::kDeleted;
  std::snprintf(status, sizeof(status),
                "frame %lld  t %.2f s  %.1f ms  pool %.0f%%  objects %d  dropped %lld%s",
                static_cast<long long>(f.index), f.timestamp, f.ms, 100.0 * f.pool_occupancy, alive,
                static_cast<long long>(f.dropped_frames), f.lost ? "  TRACKING LOST" : "");
  putLabel(tile, status, cv::Point(4, tile.rows - 4), f.lost ? kRed : kWhite, scale);
  return tile;
}

cv::Mat RunView::objectAssociationTile(const std::vector<AssociationImage>& association,
                                       cv::Size size) {
  cv::Mat acc(size, CV_32FC3, cv::Scalar(0, 0, 0));
  for (const AssociationImage& a : association) {
    if (a.id <= 0 || a.q.size() != size) continue;
    const cv::Vec3b c = objectColor(a.id);
    for (int y = 0; y < size.height; ++y) {
      const float* q = a.q.ptr<float>(y);
      cv::Vec3f* out = acc.ptr<cv::Vec3f>(y);
      for (int x = 0; x < size.width; ++x) {
        if (!std::isfinite(q[x]) || q[x] <= 0) continue;
        for (int ch = 0; ch < 3; ++ch) out[x][ch] += q[x] * c[ch];
      }
    }
  }
  cv::Mat out;
  acc.convertTo(out, CV_8UC3);  // saturating
  return out;
}

cv::Mat RunView::topView(cv::Size size) const {
  cv::Mat tile(size, CV_8UC3, cv::Scalar(30, 30, 30));
  // Bounds of every path point on the (x, z) plane, with a margin, one scale for both axes.
  double x0 = camera_position_.x(), x1 = x0, z0 = camera_position_.z(), z1 = z0;
  const auto extend = [&](const Eigen::Vector3d& p) {
    x0 = std::min(x0, p.x());
    x1 = std::max(x1, p.x());
    z0 = std::min(z0, p.z());
    z1 = std::max(z1, p.z());
  };
  for (const auto& p : camera_path_) extend(p);
  for (const auto& [id, path] : object_paths_) {
    for (const auto& p : path) extend(p);
  }
  // The drawing area leaves the title's band free (kTitleBand of the height).
  constexpr double kTitleBand = 0.12, kMargin = 1.2;
  const double area_h = size.height * (1.0 - kTitleBand);
  const double span = std::max({x1 - x0, z1 - z0, 1.0}) * kMargin;
  const double cx = 0.5 * (x0 + x1), cz = 0.5 * (z0 + z1);
  const double s = std::min<double>(size.width, area_h) / span;
  const auto pixel = [&](const Eigen::Vector3d& p) {
    return cv::Point(static_cast<int>(size.width / 2.0 + (p.x() - cx) * s),
                     static_cast<int>(size.height - area_h / 2.0 - (p.z() - cz) * s));
  };
  const auto polyline = [&](const std::vector<Eigen::Vector3d>& path, const cv::Scalar& c) {
    for (size_t i = 1; i < path.size(); ++i) {
      cv::line(tile, pixel(path[i - 1]), pixel(path[i]), c, 1, cv::LINE_AA);
    }
  };
  polyline(camera_path_, kGray);
  for (const auto& [id, path] : object_paths_) {
    const cv::Vec3b c = objectColor(id);
    polyline(path, cv::Scalar(c[0], c[1], c[2]));
    if (!path.empty()) cv::circle(tile, pixel(path.back()), 3, cv::Scalar(c[0], c[1], c[2]), -1);
  }
  const cv::Point cam = pixel(camera_position_);
  cv::circle(tile, cam, 4, kWhite, -1);
  cv::line(tile, cam, pixel(camera_position_ + 0.1 * span * camera_forward_), kWhite, 1,
           cv::LINE_AA);
  char scale_text[64];
  std::snprintf(scale_text, sizeof(scale_text), "top view (x, z)  %.1f m across", span);
  putTitle(tile, scale_text);
  return tile;
}

cv::Mat RunView::compose(const ViewFrame& f) {
  const cv::Size size = f.depth.size();
  if (f.depth.type() != CV_32F || size.width < 2 || size.height < 2) {
    throw InvalidArgument("viewer: frame " + std::to_string(f.index) +
                          ": depth must be a CV_32F image");
  }
  if (f.object_ids.type() != CV_32S || f.object_ids.size() != size) {
    throw InvalidArgument("viewer: frame " + std::to_string(f.index) +
                          ": the object id image must be CV_32S of the depth's size");
  }
  const int w = size.width, h = size.height, hw = w / 2, hh = h / 2;
  // Paths for the top view.
  camera_position_ = f.T_world_camera.translation();
  camera_forward_ = f.T_world_camera.linear().col(2);
  camera_path_.push_back(camera_position_);
  // Where each tracked object is seen: the pixel centroid of its rendered mask, at the median
  // measured depth over the mask, in the world.
  std::map<int, cv::Point2d> sum;
  std::map<int, std::vector<float>> depths;
  for (int y = 0; y < h; ++y) {
    const int32_t* ids = f.object_ids.ptr<int32_t>(y);
    const float* d = f.depth.ptr<float>(y);
    for (int x = 0; x < w; ++x) {
      if (ids[x] <= 0 || !std::isfinite(d[x]) || d[x] <= 0) continue;
      sum[ids[x]] += cv::Point2d(x, y);
      depths[ids[x]].push_back(d[x]);
    }
  }
  const core::Intrinsics& k = f.intrinsics;
  for (const ObjectOutcome& o : f.objects) {
    auto it = depths.find(o.id);
    if (o.state != ObjectState::kTracked || it == depths.end() || k.fx <= 0 || k.fy <= 0) continue;
    std::vector<float>& z = it->second;
    std::nth_element(z.begin(), z.begin() + static_cast<long>(z.size() / 2), z.end());
    const double depth = z[z.size() / 2];
    const cv::Point2d c = sum[o.id] / static_cast<double>(z.size());
    const Eigen::Vector3d p_camera((c.x - k.cx) / k.fx * depth, (c.y - k.cy) / k.fy * depth, depth);
    object_paths_[o.id].push_back(f.T_world_camera * p_camera);
  }

  cv::Mat panel(h + hh, w + hw, CV_8UC3, cv::Scalar(0, 0, 0));
  overlayTile(f).copyTo(panel(cv::Rect(0, 0, w, h)));
  topView(cv::Size(hw, hh)).copyTo(panel(cv::Rect(w, 0, hw, hh)));
  cv::Mat depth = resized(depthFalseColor(f.depth), cv::Size(hw, hh), cv::INTER_NEAREST);
  putTitle(depth, "depth (0-5 m)");
  depth.copyTo(panel(cv::Rect(w, hh, hw, hh)));

  cv::Mat q0(hh, hw, CV_8UC3, cv::Scalar(0, 0, 0));
  for (const AssociationImage& a : f.association) {
    if (a.id == 0 && a.q.size() == size) {
      q0 = resized(associationFalseColor(a.q), cv::Size(hw, hh), cv::INTER_NEAREST);
    }
  }
  putTitle(q0, "q0 background");
  q0.copyTo(panel(cv::Rect(0, h, hw, hh)));
  cv::Mat qi = resized(objectAssociationTile(f.association, size), cv::Size(hw, hh));
  putTitle(qi, "q_i objects");
  qi.copyTo(panel(cv::Rect(hw, h, hw, hh)));

  cv::Mat list(hh, hw, CV_8UC3, cv::Scalar(20, 20, 20));
  putTitle(list, "objects");
  const double scale = textScale(2 * hw);
  const int line = static_cast<int>(std::ceil(30 * scale)) + 4;
  int y = 2 * line;
  for (const ObjectOutcome& o : f.objects) {
    if (y > hh - 4) break;
    const cv::Vec3b c = objectColor(o.id);
    char text[160];
    std::snprintf(text, sizeof(text), "%d %s  %s  ex %.2f", o.id, o.class_name.c_str(),
                  objectStateName(o.state), o.existence);
    putLabel(list, text, cv::Point(6, y), cv::Scalar(c[0], c[1], c[2]), scale);
    y += line;
  }
  list.copyTo(panel(cv::Rect(w, h, hw, hh)));
  return panel;
}

}  // namespace emf::pipeline
