// Writes the frames the C API tests feed through emf_system_process_frame, in a form plain C99
// reads without image libraries: `capi_test_frames <folder>` renders synth:room (kUri) and
// writes <folder>/frames.txt (header: width height fx fy cx cy frames; then per frame:
// timestamp and the ground-truth camera pose T_first_camera, row-major 3x4, relative to the
// first camera like emf's world), depth-<i>.u16 (raw uint16, 5000 units per metre, 0 = invalid)
// and color-<i>.rgb (raw RGB888).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "core/frame_source.h"
#include "sources/open_source.h"

namespace {

constexpr const char* kUri = "synth:room?frames=12&width=160&height=120&seed=5";
constexpr double kDepthScale = 5000.0;

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: capi_test_frames <folder>\n";
    return 2;
  }
  try {
    const std::string dir = argv[1];
    std::filesystem::create_directories(dir);
    emf::core::SourceOptions options;
    auto src = emf::sources::openSource(kUri, options);
    const emf::core::Intrinsics k = src->intrinsics();
    std::ofstream list(dir + "/frames.txt");
    list.precision(17);
    list << k.width << " " << k.height << " " << k.fx << " " << k.fy << " " << k.cx << " " << k.cy
         << " " << src->size() << "\n";
    emf::core::Frame f;
    Eigen::Isometry3d T_world_first = Eigen::Isometry3d::Identity();
    for (int i = 0; src->next(f); ++i) {
      if (i == 0) T_world_first = *f.T_world_camera_gt;
      const Eigen::Isometry3d T = T_world_first.inverse() * *f.T_world_camera_gt;
      list << f.timestamp;
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 4; ++c) list << " " << T.matrix()(r, c);
      }
      list << "\n";
      std::vector<uint16_t> depth(static_cast<size_t>(k.width) * k.height);
      for (int y = 0; y < k.height; ++y) {
        for (int x = 0; x < k.width; ++x) {
          const float d = f.depth.at<float>(y, x);
          depth[static_cast<size_t>(y) * k.width + x] =
              std::isfinite(d) ? static_cast<uint16_t>(std::lround(d * kDepthScale)) : 0;
        }
      }
      char name[64];
      std::snprintf(name, sizeof(name), "/depth-%d.u16", i);
      std::ofstream(dir + name, std::ios::binary)
          .write(reinterpret_cast<const char*>(depth.data()),
                 static_cast<std::streamsize>(depth.size() * sizeof(uint16_t)));
      std::vector<unsigned char> rgb(static_cast<size_t>(k.width) * k.height * 3);
      for (int y = 0; y < k.height; ++y) {
        for (int x = 0; x < k.width; ++x) {
          const cv::Vec3b bgr = f.color.at<cv::Vec3b>(y, x);
          unsigned char* p = &rgb[(static_cast<size_t>(y) * k.width + x) * 3];
          p[0] = bgr[2];
          p[1] = bgr[1];
          p[2] = bgr[0];
        }
      }
      std::snprintf(name, sizeof(name), "/color-%d.rgb", i);
      std::ofstream(dir + name, std::ios::binary)
          .write(reinterpret_cast<const char*>(rgb.data()),
                 static_cast<std::streamsize>(rgb.size()));
    }
    std::cout << "capi_test_frames: wrote " << src->size() << " frames to " << dir << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "capi_test_frames: " << e.what() << "\n";
    return 1;
  }
}
