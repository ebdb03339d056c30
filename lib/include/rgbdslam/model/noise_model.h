#pragma once
// The measurement noise that the tracker's pose fit (pose_optimizer.h) and bundle adjustment
// (bundle_adjuster.h) share (paper sec. V): a corner found at pyramid level l is off by
// sigma = k * 2^l per axis [px at level 0] (eq. 16), a Kinect depth reading d by
// sigma = a * d^2 [m] (eq. 17). Both divide their residuals (residuals.h) by these sigmas,
// so their robust scales, cut-offs and the pose covariance are in units of them.
// Configuration: section "noise", one place for both; each component holds a copy of this
// struct and NoiseModel::bind binds the copies to the same keys (option_registry.h).
#include <cmath>
#include <string>

#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct NoiseModel {
  double sigma_2d_k = 0.987;        // k [px]: the paper's estimate
  double depth_sigma_a = 3.331e-3;  // a [1/m]: the paper's plane experiment

  // Standard deviation of a 2-D measurement found at pyramid 'level' [px at level 0].
  double sigma2d(int level) const { return std::ldexp(sigma_2d_k, level); }
  // Standard deviation of a depth reading d [m] (the measured d) [m].
  double sigmaDepth(double d) const { return depth_sigma_a * d * d; }

  void bind(OptionRegistry* registry, const std::string& section = "noise");
};

}  // namespace rgbdslam
