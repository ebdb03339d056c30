#include "rgbdslam/model/noise_model.h"

namespace rgbdslam {

void NoiseModel::bind(OptionRegistry* r, const std::string& section) {
  r->bind(section, "sigma_2d_k", &sigma_2d_k, 1e-3, 100.0, "px",
          "2-D measurement noise: sigma = k * 2^level per axis (tracker pose and bundle adjustment)");
  r->bind(section, "depth_sigma_a", &depth_sigma_a, 1e-6, 1.0, "1/m",
          "depth noise: sigma = a * d^2 (tracker pose and bundle adjustment)");
}

}  // namespace rgbdslam
