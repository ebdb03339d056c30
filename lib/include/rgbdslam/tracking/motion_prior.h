#pragma once
// A constant-velocity motion prior for the pose fit (issues 10 and 11: the flight's weak
// stretches). PTAM's motion model only starts the search; the fit then follows the points
// found wherever they lead. Where the points fix a direction of the pose poorly (far walls
// beyond the depth range cannot tell a sideways step from a turn; a corridor's walls and
// floor, parallel to the motion, leave the forward step to a few corners), a handful of
// wrong matches can carry the pose off in that direction while the fit reports it fixed
// (docs/open_work.md, sessions 15, 16 and 22). A vehicle cannot jump: its pose follows from
// the last poses within what its acceleration allows. That is the prior.
//
// Model: a Kalman filter on the pose T_c_w (left perturbation, as the fit's, pose_optimizer.h)
// and the velocity v (a twist per second, T_c_w(t + dt) = exp(v dt) T_c_w(t)), with a
// piecewise-constant random acceleration of standard deviation a (translation, m/s^2) and
// alpha (rotation, rad/s^2) over each frame interval dt:
//   predict: T- = exp(v dt) T, v- = v, P- = F P F^T + Q, F = [I dt I; 0 I],
//            Q = sigma^2 [dt^4/4 I, dt^3/2 I; dt^3/2 I, dt^2 I] per axis (sigma = a or alpha);
//   the fit: minimises the measurements' cost plus (T - T-)^T (P-_TT)^-1 (T - T-), so the
//            points decide wherever they fix the pose, and the prior only where they do not;
//   update:  with H the measurements' information at the fitted T+ (the fit's J^T W J),
//            P+_TT = ((P-_TT)^-1 + H)^-1, and the velocity by Gaussian conditioning on the
//            pose: v+ = v- + K (T+ - T-), K = P-_vT (P-_TT)^-1,
//            P+_vv = P-_vv - K P-_Tv + K P+_TT K^T, P+_vT = K P+_TT.
// The adjoint of the predicted motion is left out of F (a frame's motion is small).
// The tracker passes update() the accepted pose, the fit of the inliers without the prior
// (below), not the fit with it: the filter's pose is re-anchored to the map's each frame,
// and the velocity follows by the conditioning above as if that pose were the posterior.
// This lets the accepted pose's own noise into the velocity (a review simulated twice the
// velocity noise of an exact update in a weakly measured direction). Passing the fit with
// the prior instead, the exact posterior, was measured on flight 720 worlds 1-10: world 7
// drifted from frame 680 and was lost at 706 (53.9 mm), the nine others as good; the
// filter's own pose then slides from the map's where the points fix it poorly, and its
// prior with it. Re-anchored, it stays on the map.
//
// Reset (no velocity known: the first frame, a relocalisation): v = 0 with the standard
// deviation of the vehicle's top speed, so the prior of the next frame is weak (3 m/s over
// 1/30 s: 10 cm) and two frames later the velocity comes from the poses. A lost frame, time
// going back, or a gap over max_gap_s also reset it.
//
// How the tracker uses it (MotionPriorOptions::in_final_fit false, the default): the fit
// with the prior decides which matches are inliers, and a fit of those inliers without it
// gives the frame's pose. Wrong matches that agree with each other (near ghosts of far
// walls, which pull the pose back by centimetres a frame in the flight's corridor C1) are
// the prior's to refuse; the pose itself stays the one the map's points give, because the
// next keyframe's points are placed from it and must agree with the map they join. Kept in
// the final fit as well, the prior made the synthetic corridor's first 900 frames 20 %
// worse over six worlds (ATE 11.9 against 9.9 mm): the points' errors are the map's, shared
// from frame to frame, so a pose held smooth against them is off the map locally. A frame
// held by depth (depth_alignment.h) keeps the prior in its fit: its points are too few to
// choose from, and the surfaces leave the motion along them unfixed.
//
// What the prior does not do: it adds nothing to the pose's reported uncertainty, which
// stays the measurements' own (the loss rules and the state reported to the flight
// controller are vision's, not dead reckoning's).
#include <cstdint>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "rgbdslam/geometry/se3.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

using Mat6 = Eigen::Matrix<double, 6, 6>;

struct MotionPriorOptions {
  bool enabled = true;
  // The vehicle's random acceleration, one standard deviation. A MAV manoeuvres at up to
  // about 1 g; 5 m/s^2 keeps 95 % of such steps within two sigmas, so a real acceleration
  // is not fought where the points fix the pose. Per frame at 30 Hz that is 2.8 mm.
  double accel_m_s2 = 5.0;           // [m/s^2]
  // Rotation: the flight's 90 deg/s spins start within 0.25 s (6 rad/s^2); a hand-held
  // camera shakes faster. Points fix rotation well almost everywhere; 20 rad/s^2 (0.6 deg a
  // frame) leaves it to them.
  double angular_accel_rad_s2 = 20.0;  // [rad/s^2]
  // The vehicle's top speed and turn rate: the velocity's sigma after a reset, and the most
  // the dead reckoning while lost takes (depth_dead_reckoning.h).
  double max_speed_m_s = 3.0;   // [m/s]
  double max_rate_rad_s = 3.0;  // [rad/s]
  double max_gap_s = 0.5;              // a longer time between two poses resets [s]
  // Frames closer in time than this are taken as the same instant (a driver's burst of
  // frames stamped on arrival): no prior, and the filter only takes the newer pose [s].
  double min_gap_s = 0.005;
  // Whether the prior stays in the fit that gives the frame's pose, or only chooses the
  // matches (the fit with it decides the inliers, a fit of those without it the pose).
  bool in_final_fit = false;

  void bind(OptionRegistry* registry, const std::string& section);  // as motion_prior_*
};

// What the fit adds to its cost: (T - T_c_w)^T information (T - T_c_w), T - T_c_w taken as
// log(T T_c_w^-1).
struct PosePrior {
  SE3 T_c_w;
  Mat6 information = Mat6::Zero();
};

class MotionPrior {
 public:
  explicit MotionPrior(const MotionPriorOptions& options = {}) : options_(options) {}

  // The prior for a frame at 'utime', if there is one (enabled, a pose known, the gap in
  // range). Does not change the filter.
  std::optional<PosePrior> predict(int64_t utime) const;
  // A pose accepted at 'utime': T_c_w the fit with the prior predict(utime) gave (if any),
  // the posterior's mean; 'measured' the measurements' information (normalised J^T W J,
  // without the prior). Negative eigenvalues of 'measured' count as zero.
  void update(int64_t utime, const SE3& T_c_w, const Mat6& measured);
  // Forget the velocity and restart from this pose (a relocalisation, the first frame).
  void reset(int64_t utime, const SE3& T_c_w, const Mat6& measured);
  // The world frame moved (a map correction the tracker follows): new = T_new_old * old.
  // The velocity and the covariances, in the camera's frame, stay.
  void moveWorld(const SE3& T_new_old) { T_c_w_ = T_c_w_ * T_new_old.inverse(); }
  // Forget everything (lost).
  void clear() { have_pose_ = false; }
  // The velocity replaced, the covariances kept: the dead reckoning keeps the velocity where
  // its measurement fixes nothing (depth_dead_reckoning.h).
  void setVelocity(const Vec6& v) { v_ = v; }

  bool hasPose() const { return options_.enabled && have_pose_; }
  const Vec6& velocity() const { return v_; }  // [m/s, rad/s], twist on T_c_w
  // The last pose taken (update or reset) and its time; meaningful only with hasPose().
  const SE3& pose() const { return T_c_w_; }
  int64_t utime() const { return utime_; }
  const MotionPriorOptions& options() const { return options_; }

 private:
  using Mat12 = Eigen::Matrix<double, 12, 12>;
  // The predicted state and covariance at 'dt' after the last pose.
  void propagate(double dt, SE3* T, Vec6* v, Mat12* P) const;
  std::optional<double> gapS(int64_t utime) const;

  MotionPriorOptions options_;
  bool have_pose_ = false;
  int64_t utime_ = 0;
  SE3 T_c_w_;
  Vec6 v_ = Vec6::Zero();
  Mat12 P_ = Mat12::Zero();
};

}  // namespace rgbdslam
