#pragma once
// Camera pose from 2-D (and optionally depth) measurements of known map points: PTAM's
// tracker pose update, iteratively re-weighted Gauss-Newton with Tukey's biweight. Why: the
// patch search yields some wrong matches; Tukey gives them zero weight, with the scale
// re-estimated from the median error at every iteration (PTAM), so the fit is not dragged
// by them. Depth residuals (paper sec. IV-E) use their own robust scale, so a bad depth
// reading does not discard the good 2-D measurement of the same point.
//
// The median scale is only robust while outliers are fewer than half the residuals at the
// current pose. With many wrong matches (fine texture, fur) the fit can settle where the
// wrong matches pull it: there the correct matches' errors are large too, the median is
// large, the cut-off admits everything and the wrong pose explains itself. So, as PTAM
// does ("force the M-estimator to be brutal" after the fifth iteration), the first
// free_scale_iterations use the median scale alone (a wide basin for a poor start) and
// the later ones cap it at max_robust_sigma measurement sigmas: the residuals are
// normalised by their known noise, so a correct pose has a scale near 1 whatever the
// outliers, and matches beyond tukey_c times the cap get no weight. The fit does not stop
// on a small step before the cap has been applied.
//
// Call order: fill PoseObservations, optimisePose(camera, T_c_w_start, observations, options).
// Frames and units: T_c_w maps world to camera (the residuals' convention, model/residuals.h),
// updated by the left perturbation T_c_w <- exp(xi) T_c_w. Pixels at level 0, depth in m.
#include <vector>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/geometry/se3.h"
#include "rgbdslam/model/noise_model.h"
#include "rgbdslam/tracking/motion_prior.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct PoseObservation {
  Vec3 p_w = Vec3::Zero();                       // map point [m]
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  // measured pixel, level 0 [px]
  int level = 0;                                 // pyramid level found at (its sigma)
  double depth = 0.0;                            // measured depth [m]; 0 = none
};

struct PoseOptimizerOptions {
  int iterations = 10;                // Gauss-Newton iterations per stage at most
  double tukey_c = 4.6851;            // cut-off in robust sigmas
  double min_robust_sigma = 0.4;      // floor of the robust scale [measurement sigmas]
  double max_robust_sigma = 1.0;      // cap of the robust scale after the free
                                      // iterations [measurement sigmas]; 0: no cap
  int free_scale_iterations = 5;      // iterations with the uncapped median scale
  // Add the depth residuals of observations with a reading. The tracker turns this off in
  // mono, where depth serves only the first frame (slam_mode.h).
  bool use_depth = true;
  NoiseModel noise;                   // measurement sigmas (bound as section "noise")
  double converged_step = 1e-7;       // stop when |xi| is below this [-]

  void bind(OptionRegistry* registry, const std::string& section);  // keys of the tracker's
};

struct PoseOptimizerResult {
  SE3 T_c_w;
  bool ok = false;        // false: too few usable observations or a singular system
  int inliers_2d = 0;     // 2-D residuals with a non-zero final weight
  int inliers_depth = 0;  // depth residuals with a non-zero final weight
  int extra_residuals = 0;  // ScalarResiduals of the last iteration
  int inliers_extra = 0;    // ...with a non-zero final weight
  int iterations = 0;     // iterations run
  // J^T W J of the last iteration in normalised units (residuals divided by their sigmas),
  // so its inverse is the pose covariance for the left perturbation xi = (v, w) [m, rad]
  // when the measurement sigmas are right. Zero when not ok.
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  // The ScalarResiduals' share of 'information' (zero without them).
  Eigen::Matrix<double, 6, 6> extra_information = Eigen::Matrix<double, 6, 6>::Zero();
};

// Standard deviations of a pose from its information matrix: the largest over directions
// of the translation part [m] and of the rotation part [rad]; infinite when singular.
struct PoseUncertainty {
  double translation_m = 0.0;
  double rotation_rad = 0.0;
};
PoseUncertainty poseUncertainty(const Eigen::Matrix<double, 6, 6>& information);

// Further scalar residuals of the pose, re-linearised at every iteration (their data
// association may change with the pose): normalised residuals (divided by their sigmas)
// and their Jacobians for the left perturbation. They get their own robust scale, like the
// depth residuals. E.g. point-to-plane against depth (depth_alignment.h).
class ScalarResiduals {
 public:
  virtual ~ScalarResiduals() = default;
  virtual void linearise(const SE3& T_c_w, std::vector<double>* r,
                         std::vector<Eigen::Matrix<double, 1, 6>>* J) const = 0;
};

// Minimises sum rho(|e2| / sigma2d(level)) + sum rho(|ed| / sigmaDepth(d)) (+ sum rho of
// 'extra', if given) (+ the quadratic 'prior', if given: motion_prior.h) over T_c_w. inlier
// (optional) receives one flag per observation: its 2-D residual kept a weight. Without
// 'extra' at least 3 observations are needed; with it, what the residuals fix is up to the
// caller (see the information matrix). The prior moves the pose but is not part of the
// information reported: that stays the measurements' own.
PoseOptimizerResult optimisePose(const PinholeCamera& camera, const SE3& T_c_w_start,
                                 const std::vector<PoseObservation>& observations,
                                 const PoseOptimizerOptions& options,
                                 std::vector<uint8_t>* inlier = nullptr,
                                 const ScalarResiduals* extra = nullptr,
                                 const PosePrior* prior = nullptr);

// Tukey's biweight for a squared normalised error e2 and squared cut-off c2:
// (1 - e2 / c2)^2 inside the cut-off, 0 outside.
inline double tukeyWeight(double e2, double c2) {
  if (e2 >= c2) return 0.0;
  const double t = 1.0 - e2 / c2;
  return t * t;
}

// Robust squared scale of squared normalised errors: max(floor^2, 1.4826^2 median(e2)),
// and at most cap^2 when cap_sigma > 0. 'e2' is reordered.
double robustSigmaSquared(std::vector<double>* e2, double floor_sigma, double cap_sigma = 0.0);

}  // namespace rgbdslam
