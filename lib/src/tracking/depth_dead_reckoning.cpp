#include "rgbdslam/tracking/depth_dead_reckoning.h"

#include <algorithm>

#include <Eigen/Eigenvalues>

#include "rgbdslam/map/map.h"

namespace rgbdslam {
namespace {

// The chi-square value that 99.9 % of 6-dimensional Gaussian errors stay below: a fit
// further from the prediction, in the prediction's own covariance, is refused.
constexpr double kChi2Dof6P999 = 22.458;

}  // namespace

DepthDeadReckoning::DepthDeadReckoning(const PinholeCamera& camera, const DepthAlignmentOptions& align,
                                       const PoseOptimizerOptions& pose, double min_depth_m, double max_depth_m,
                                       double fixed_sigma_m, double fixed_sigma_rad)
    : camera_(camera), align_(align), pose_(pose), min_depth_m_(min_depth_m), max_depth_m_(max_depth_m) {
  bar_.diagonal() << Vec3::Constant(1.0 / (fixed_sigma_m * fixed_sigma_m)),
      Vec3::Constant(1.0 / (fixed_sigma_rad * fixed_sigma_rad));
}

void DepthDeadReckoning::start(const MotionPrior& at_last_pose) {
  stop();
  if (!at_last_pose.hasPose()) return;
  prior_ = at_last_pose;
  running_ = true;
}

void DepthDeadReckoning::stop() {
  running_ = false;
  held_ = 0;
  reference_.clear();
}

std::optional<SE3> DepthDeadReckoning::predict(int64_t utime) const {
  if (!running_) return std::nullopt;
  const std::optional<PosePrior> predicted = prior_.predict(utime);
  if (!predicted) return std::nullopt;
  return predicted->T_c_w;
}

bool DepthDeadReckoning::step(const RgbdFrame& frame, const std::vector<SurfaceAnchor>& map_anchors) {
  if (!running_) return false;
  const double dt_s = static_cast<double>(frame.utime - prior_.utime()) * 1e-6;
  if (dt_s < 0.0 || dt_s > prior_.options().max_gap_s) {
    running_ = false;  // time went back, or nothing held for too long: the velocity is stale
    return false;
  }
  const std::optional<PosePrior> predicted = prior_.predict(frame.utime);
  if (!predicted || frame.depth.empty()) return false;
  anchors_ = map_anchors;
  if (!reference_.empty()) appendAnchors(reference_, T_w_reference_, &anchors_);
  if (anchors_.empty()) return false;
  const PointToPlaneResiduals planes(anchors_, frame, camera_, pose_.noise, min_depth_m_, max_depth_m_,
                                     align_.max_incidence_deg);
  const PoseOptimizerResult fit = optimisePose(camera_, predicted->T_c_w, {}, pose_, nullptr, &planes, &*predicted);
  if (!fit.ok || fit.inliers_extra < align_.min_inliers ||
      fit.inliers_extra < align_.min_inlier_ratio * fit.extra_residuals) {
    return false;
  }
  // In the directions the surfaces do not fix (the slide along a corridor, the turn about a
  // lone plane's normal) the fit's move is their noise and edge effects, not the camera's:
  // a slide that takes samples out of the image lowers the cost. Left to the fit, such a
  // slide fed the velocity, which fed the next slide: metres off within a second (a room's
  // corner with the camera turning away from one wall). The prediction stays in those
  // directions ("solution remapping", Zhang, Kaess and Singh, ICRA 2016). A direction is
  // fixed where the surfaces' honest information holds it within fixed_sigma_* (1 sigma):
  // generalised eigenvalues of that information over the bar's (bar_) of at least 1.
  // (Against the prediction's information instead, the bar fell with the prediction's
  // growing uncertainty, and edge effects passed it: 2.5 m off after 1.5 s in the same
  // corner.) The move kept must lie within the prediction's 99.9 % ellipsoid.
  const Mat6 honest = planes.honestInformation(fit.extra_information, align_.effective_samples, fit.inliers_extra);
  const Eigen::GeneralizedSelfAdjointEigenSolver<Mat6> directions(0.5 * (honest + honest.transpose()), bar_);
  if (directions.info() != Eigen::Success) return false;
  const Vec6 fitted = (fit.T_c_w * predicted->T_c_w.inverse()).log();
  Mat6 onto_kept = Mat6::Zero();  // projects onto the directions kept, along the others
  Mat6 fixed = Mat6::Zero();      // the honest information in the directions kept
  int kept = 0;
  for (int i = 0; i < 6; ++i) {
    const double lambda = directions.eigenvalues()(i);
    if (!(lambda >= 1.0)) continue;
    const Vec6 u = directions.eigenvectors().col(i);  // u^T bar u = 1, u^T honest u = lambda
    const Vec6 b = bar_ * u;
    onto_kept += u * b.transpose();
    fixed += lambda * b * b.transpose();
    ++kept;
  }
  if (kept == 0) return false;  // the surfaces fix nothing: the frame tells nothing
  const Vec6 moved = onto_kept * fitted;  // the surfaces' move, in the directions kept
  if (moved.dot(predicted->information * moved) > kChi2Dof6P999) return false;
  // The move taken weighs the surfaces' honest information against the prediction's, as
  // the Kalman filter's mean would (the kept part of it, the other directions left free).
  // The fit weighs every sample as independent, so the prediction in it counts for little
  // and it takes nearly the whole move even where the honest information is barely over
  // the bar: there a few centimetres of depth noise through the samples' normals are the
  // move, and divided by a frame's time they were a velocity of a metre a second (a lone
  // wall in test_depth_dead_reckoning.cpp). The prediction is thereby counted twice where
  // the samples do not outweigh it: the move taken errs towards the prediction.
  const Vec6 off = onto_kept * (predicted->information + fixed).ldlt().solve(fixed * moved);
  const SE3 T_c_w = SE3::exp(off) * predicted->T_c_w;
  // The velocity changes only in the directions kept, as the pose does. Conditioned on the
  // whole pose, the frame's noise in the directions kept reached the velocity in the others
  // through their covariance, and nothing there pulled it back: on the 10-minute flight,
  // with five directions kept, the turn about the camera's axis spun up to 350 deg/s
  // within a second, and the pose with it (docs/open_work.md, session 39). Elsewhere the
  // velocity stays as it was. The covariances are the update's, conditioned on the whole
  // pose: in the other directions they shrink through the correlations while the mean
  // stays, so the filter is somewhat overconfident there (an approximation, kept simple).
  const Vec6 v_before = prior_.velocity();
  MotionPrior updated = prior_;
  updated.update(frame.utime, T_c_w, fixed);
  const Vec6 v = v_before + onto_kept * (updated.velocity() - v_before);
  // A speed or turn rate beyond the vehicle's (MotionPriorOptions::max_speed_m_s,
  // max_rate_rad_s), and higher than before this frame, is a fit in another basin that
  // the prediction's ellipsoid let through after frames not held had widened it. (Already
  // beyond at the loss, a frame that slows it is still held.)
  const auto beyond = [](const Vec3& now, const Vec3& before, double top) {
    return now.norm() > top && now.norm() > before.norm();
  };
  if (beyond(v.head<3>(), v_before.head<3>(), prior_.options().max_speed_m_s) ||
      beyond(v.tail<3>(), v_before.tail<3>(), prior_.options().max_rate_rad_s)) {
    return false;
  }
  updated.setVelocity(v);
  prior_ = updated;
  // A new reference once the camera has moved on from the last one (DepthAlignmentOptions::
  // reference_step_*), not every frame: each passes its alignment error on. A step of 0
  // turns the reference off, as in depth-aided tracking: the keyframes' surfaces alone.
  const SE3 T_w_c = T_c_w.inverse();
  if (align_.reference_step_m <= 0.0) {
    reference_.clear();
  } else if (reference_.empty() ||
      (T_w_c.translation() - T_w_reference_.translation()).norm() >= align_.reference_step_m ||
      T_w_c.rotation().angularDistance(T_w_reference_.rotation()) >= align_.reference_step_deg * M_PI / 180.0) {
    reference_ = sampleSurface(depthToMetres(frame.depth, frame.depth_scale, min_depth_m_, max_depth_m_), camera_,
                               pose_.noise, align_);
    T_w_reference_ = T_w_c;
  }
  ++held_;
  return true;
}

std::optional<SE3> DepthDeadReckoning::poseAt(int64_t utime, double max_coast_s) const {
  if (held_ == 0) return std::nullopt;
  const double dt_s = std::clamp(static_cast<double>(utime - prior_.utime()) * 1e-6, 0.0, std::max(0.0, max_coast_s));
  return SE3::exp(dt_s * prior_.velocity()) * prior_.pose();
}

bool DepthDeadReckoning::heldRecently(int64_t utime) const {
  return held_ > 0 && utime >= prior_.utime() &&
         static_cast<double>(utime - prior_.utime()) * 1e-6 <= prior_.options().max_gap_s;
}

void DepthDeadReckoning::moveWorld(const SE3& T_new_old) {
  prior_.moveWorld(T_new_old);
  T_w_reference_ = T_new_old * T_w_reference_;
}

}  // namespace rgbdslam
