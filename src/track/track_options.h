// Options of preprocessing (section `preprocess`) and pose tracking (section `track`).
#pragma once

#include "common/option_binder.h"

namespace emf::track {

struct PreprocessOptions {
  double sigma_depth_m = 0.04;
  double sigma_space_px = 4.5;
  int bilateral_radius_px = 3;  // 7x7 window
  double min_depth_m = 0.1;
  double max_depth_m = 5.0;

  void bind(OptionBinder& b) {
    b.real("sigma_depth_m", sigma_depth_m, 1e-4, 10.0, "m", "bilateral filter range sigma");
    b.real("sigma_space_px", sigma_space_px, 0.1, 50.0, "px", "bilateral filter spatial sigma");
    b.integer("bilateral_radius_px", bilateral_radius_px, 0, 10, "px",
              "bilateral half window (3 = 7x7, 0 = off)");
    b.real("min_depth_m", min_depth_m, 0.0, 100.0, "m", "depths below are invalid");
    b.real("max_depth_m", max_depth_m, 0.01, 100.0, "m", "depths above are invalid");
  }
};

struct TrackOptions {
  int max_iterations = 100;
  double lm_tau = 1e3;
  double lm_eps = 1e-8;
  double lm_nu = 2.0;
  /// Huber threshold as a fraction of the truncation distance (0.2 x 10 voxels = 2 voxels).
  double huber_truncation_factor = 0.2;

  void bind(OptionBinder& b) {
    b.integer("max_iterations", max_iterations, 1, 1000, "", "LM iterations per frame and volume");
    b.real("lm_tau", lm_tau, 1e-12, 1e12, "", "LM initial damping scale");
    b.real("lm_eps", lm_eps, 0.0, 1.0, "", "LM convergence threshold on the increment");
    b.real("lm_nu", lm_nu, 1.0, 100.0, "", "LM damping growth factor");
    b.real("huber_truncation_factor", huber_truncation_factor, 0.0, 10.0, "truncation",
           "Huber delta as a fraction of the truncation distance");
  }
};

}  // namespace emf::track
