#include "pipeline/object_outputs.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <opencv2/imgproc.hpp>

#include "common/error.h"
#include "common/log.h"
#include "io/atomic_output.h"
#include "io/ply.h"
#include "map/mesh.h"
#include "map/volume_host_access.h"

namespace emf::pipeline {

namespace {

// Golden angle as a fraction of the hue circle: successive ids land far apart in hue.
constexpr double kGoldenHueStep = 0.381966011250105;

}  // namespace

cv::Vec3b objectColor(int id) {
  const double hue = std::fmod(static_cast<double>(id) * kGoldenHueStep, 1.0);  // [0, 1)
  // Alternate two saturation/value levels so neighbours in hue also differ in brightness.
  const bool odd = (id % 2) != 0;
  cv::Mat hsv(1, 1, CV_8UC3,
              cv::Scalar(hue * 180.0, odd ? 255 : 200, odd ? 255 : 220));  // OpenCV H in [0, 180)
  cv::Mat bgr;
  cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
  return bgr.at<cv::Vec3b>(0, 0);
}

cv::Mat objectOverlay(const cv::Mat& color, const cv::Mat& object_ids) {
  if (object_ids.type() != CV_32S) {
    throw InvalidArgument("object id image must be CV_32S (got type " +
                          std::to_string(object_ids.type()) + ")");
  }
  cv::Mat base;
  if (color.empty()) {
    base = cv::Mat(object_ids.size(), CV_8UC3, cv::Scalar(0, 0, 0));
  } else if (color.type() != CV_8UC3) {
    throw InvalidArgument("colour image must be CV_8UC3 BGR (got type " +
                          std::to_string(color.type()) + ")");
  } else if (color.size() != object_ids.size()) {
    cv::resize(color, base, object_ids.size(), 0, 0, cv::INTER_LINEAR);
  } else {
    base = color.clone();
  }
  std::map<int32_t, cv::Vec3b> colors;  // objectColor() converts through a cv::Mat: once per id
  for (int y = 0; y < base.rows; ++y) {
    const int32_t* ids = object_ids.ptr<int32_t>(y);
    cv::Vec3b* px = base.ptr<cv::Vec3b>(y);
    for (int x = 0; x < base.cols; ++x) {
      if (ids[x] <= 0) continue;
      auto it = colors.find(ids[x]);
      if (it == colors.end()) it = colors.emplace(ids[x], objectColor(ids[x])).first;
      const cv::Vec3b c = it->second;
      for (int ch = 0; ch < 3; ++ch) {
        px[x][ch] =
            cv::saturate_cast<uint8_t>((1.0 - kOverlayAlpha) * px[x][ch] + kOverlayAlpha * c[ch]);
      }
    }
  }
  return base;
}

cv::Mat associationFalseColor(const cv::Mat& q) {
  if (q.type() != CV_32F) {
    throw InvalidArgument("association map must be CV_32F (got type " + std::to_string(q.type()) +
                          ")");
  }
  cv::Mat gray(q.size(), CV_8U);
  cv::Mat valid(q.size(), CV_8U);
  for (int y = 0; y < q.rows; ++y) {
    const float* src = q.ptr<float>(y);
    uint8_t* g = gray.ptr<uint8_t>(y);
    uint8_t* v = valid.ptr<uint8_t>(y);
    for (int x = 0; x < q.cols; ++x) {
      const bool ok = std::isfinite(src[x]);
      v[x] = ok ? 255 : 0;
      g[x] = ok ? cv::saturate_cast<uint8_t>(std::lround(255.0 * std::clamp(src[x], 0.f, 1.f))) : 0;
    }
  }
  cv::Mat out;
  cv::applyColorMap(gray, out, cv::COLORMAP_JET);
  out.setTo(cv::Scalar(0, 0, 0), valid == 0);
  return out;
}

ObjectOutputs::ObjectOutputs(std::string dir, bool binary_ply, std::string run_id)
    : dir_(std::move(dir)), binary_ply_(binary_ply), run_id_(std::move(run_id)) {}

std::string ObjectOutputs::trajectoryName(int id) {
  return "object-" + std::to_string(id) + ".txt";
}

std::string ObjectOutputs::meshName(int id) { return "object-" + std::to_string(id) + ".ply"; }

std::string ObjectOutputs::imageName(int64_t frame_index, const std::string& what) {
  char index[32];
  std::snprintf(index, sizeof(index), "%06lld", static_cast<long long>(frame_index));
  return std::string("images/") + index + "-" + what + ".png";
}

void ObjectOutputs::ensureDir(const std::string& dir) const {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw IoError(dir + ": cannot create the output folder: " + ec.message());
}

void ObjectOutputs::appendPose(Track& t, double timestamp,
                               const Eigen::Isometry3d& T_object_camera) {
  if (t.summary.deleted) return;  // its file is complete and closed: never reopened (truncated)
  if (!t.T_object_camera) {
    ensureDir(dir_);
    const int id = t.summary.id;
    t.T_object_camera = std::make_unique<io::TrajectoryStream>(
        dir_ + "/" + trajectoryName(id),
        "object " + std::to_string(id) + " (" + t.summary.class_name +
            "): T_object_camera, the camera pose in the object's frame (emf run" +
            (run_id_.empty() ? "" : " " + run_id_) + ")");
    t.summary.trajectory_file = trajectoryName(id);
  }
  // TUM files need increasing stamps: a repeated source timestamp keeps the first pose.
  t.T_object_camera->append(timestamp, T_object_camera);
}

void ObjectOutputs::add(const FrameOutcome& outcome) {
  // Objects confirmed in this frame: their poses since creation come first.
  for (const ConfirmedObject& c : outcome.confirmed) {
    Track& t = tracks_[c.id];
    ObjectSummary& s = t.summary;
    s.id = c.id;
    s.class_name = c.class_name;
    for (const ConfirmedObject::Pose& p : c.earlier) {
      if (s.first_frame < 0) {
        s.first_frame = p.index;
        s.first_timestamp = p.timestamp;
      }
      s.last_frame = p.index;
      s.last_timestamp = p.timestamp;
      ++s.frames_tracked;
      appendPose(t, p.timestamp, p.T_object_camera);
    }
  }
  for (const ObjectOutcome& o : outcome.objects) {
    Track& t = tracks_[o.id];
    ObjectSummary& s = t.summary;
    s.id = o.id;
    if (!o.class_name.empty()) s.class_name = o.class_name;
    s.existence = o.existence;
    s.T_world_object = o.T_world_object;
    switch (o.state) {
      case ObjectState::kTracked:
        if (s.first_frame < 0) {
          s.first_frame = outcome.index;
          s.first_timestamp = outcome.timestamp;
        }
        s.last_frame = outcome.index;
        s.last_timestamp = outcome.timestamp;
        ++s.frames_tracked;
        appendPose(t, outcome.timestamp, o.T_object_camera);
        break;
      case ObjectState::kLost:
        ++s.frames_lost;
        break;
      case ObjectState::kInvisible:
        ++s.frames_invisible;
        break;
      case ObjectState::kDormant:
        ++s.frames_dormant;
        break;
      case ObjectState::kDeleted:
        s.deleted = true;
        s.deleted_frame = outcome.index;
        s.deleted_timestamp = outcome.timestamp;
        s.deleted_reason = o.deleted_reason;
        // Its trajectory is complete: synced and closed, so a long run with many objects
        // coming and going holds one file open per live object only.
        if (t.T_object_camera) {
          t.T_object_camera->sync();
          t.T_object_camera.reset();
        }
        break;
    }
  }
}

void ObjectOutputs::writeMesh(int id, const map::VolumeHostView& volume,
                              const Eigen::Isometry3d& T_volume_initial) {
  ensureDir(dir_);
  // The object's frame is the volume frame at creation (a translation away after growth):
  // the frame of object-<id>.txt, placed in the world by T_world_object.
  Eigen::Isometry3d T_object_volume = Eigen::Isometry3d::Identity();
  T_object_volume.translation() = T_volume_initial.inverse().translation();
  map::MeshOptions options;
  options.world_frame = true;  // "world" = the object's frame here
  io::PlyWriter ply(dir_ + "/" + meshName(id), binary_ply_);
  map::extractMesh(volume, T_object_volume, options, ply);
  ply.commit();
  Track& t = tracks_[id];
  t.summary.id = id;
  t.summary.mesh_file = meshName(id);
}

void ObjectOutputs::onObjectDeleted(int id, const map::Volume& volume) {
  const map::VolumeHostAccess access(volume);
  writeMesh(id, access.view(), access.T_volume_initial());
}

void ObjectOutputs::writeFrameImages(const FrameOutcome& outcome, const cv::Mat& color,
                                     const cv::Mat& object_ids,
                                     const std::vector<AssociationImage>& association) {
  const std::string frame = "frame " + std::to_string(outcome.index);
  if (!object_ids.empty() && object_ids.type() != CV_32S) {
    throw InvalidArgument(frame + ": the rendered object ids must be CV_32S (got type " +
                          std::to_string(object_ids.type()) + ")");
  }
  if (!color.empty() && color.type() != CV_8UC3) {
    throw InvalidArgument(frame + ": the colour image must be CV_8UC3 BGR (got type " +
                          std::to_string(color.type()) + ")");
  }
  for (const AssociationImage& a : association) {
    if (a.q.type() != CV_32F) {
      throw InvalidArgument(frame + ": association map of volume " + std::to_string(a.id) +
                            " must be CV_32F (got type " + std::to_string(a.q.type()) + ")");
    }
    if (!object_ids.empty() && a.q.size() != object_ids.size()) {
      throw InvalidArgument(frame + ": association map of volume " + std::to_string(a.id) + " is " +
                            std::to_string(a.q.cols) + "x" + std::to_string(a.q.rows) +
                            ", the id image " + std::to_string(object_ids.cols) + "x" +
                            std::to_string(object_ids.rows));
    }
  }
  ensureDir(dir_ + "/images");
  if (!object_ids.empty()) {
    io::writeImageAtomically(dir_ + "/" + imageName(outcome.index, "objects"),
                             objectOverlay(color, object_ids));
  } else if (!color.empty()) {
    io::writeImageAtomically(dir_ + "/" + imageName(outcome.index, "objects"), color);
  }
  for (const AssociationImage& a : association) {
    io::writeImageAtomically(dir_ + "/" + imageName(outcome.index, "q" + std::to_string(a.id)),
                             associationFalseColor(a.q));
  }
}

void ObjectOutputs::writeLiveMeshes(const std::function<const map::Volume*(int id)>& volume_of) {
  for (auto& [id, t] : tracks_) {
    if (t.summary.deleted || !volume_of) continue;
    if (const map::Volume* v = volume_of(id)) onObjectDeleted(id, *v);
  }
}

void ObjectOutputs::finish(const std::function<const map::Volume*(int id)>& volume_of) {
  for (auto& [id, t] : tracks_) {
    if (t.summary.deleted && t.summary.mesh_file.empty()) {
      logWarning("object ", id, " was deleted in frame ", t.summary.deleted_frame,
                 " without onObjectDeleted(): no ", meshName(id), " (its volume is gone)");
    }
  }
  writeLiveMeshes(volume_of);
  sync();
}

void ObjectOutputs::sync() {
  for (auto& [id, t] : tracks_) {
    if (t.T_object_camera) t.T_object_camera->sync();
  }
}

std::vector<ObjectSummary> ObjectOutputs::summaries() const {
  std::vector<ObjectSummary> out;
  out.reserve(tracks_.size());
  for (const auto& [id, t] : tracks_) out.push_back(t.summary);
  return out;
}

}  // namespace emf::pipeline
