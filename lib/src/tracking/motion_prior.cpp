#include "rgbdslam/tracking/motion_prior.h"

#include <Eigen/Dense>
#include <cmath>

namespace rgbdslam {
namespace {

// Added to the measurements' information where a pose starts the filter, so that a
// direction they do not fix gets a standard deviation of 1 m (1 rad) instead of none.
constexpr double kStartInformation = 1.0;

Mat6 inverseSpd(const Mat6& m) {
  return m.ldlt().solve(Mat6::Identity());
}

// The nearest positive semi-definite matrix: a depth-aided fit's information (the points'
// plus the surfaces' honest share, depth_alignment.h) is a difference and may be indefinite.
Mat6 clampPsd(const Mat6& m) {
  if (!m.allFinite()) return Mat6::Zero();
  const Eigen::SelfAdjointEigenSolver<Mat6> eig(0.5 * (m + m.transpose()));
  if (eig.info() != Eigen::Success) return Mat6::Zero();
  return eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
}

bool positiveDefinite(const Mat6& m) {
  if (!m.allFinite()) return false;
  const Eigen::SelfAdjointEigenSolver<Mat6> eig(0.5 * (m + m.transpose()), Eigen::EigenvaluesOnly);
  return eig.info() == Eigen::Success && eig.eigenvalues().minCoeff() > 0.0;
}

}  // namespace

void MotionPriorOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "motion_prior", &enabled,
          "the pose fit's matches are chosen with a constant-velocity prediction held within the "
          "vehicle's acceleration, so wrong matches that agree with each other are refused "
          "(motion_prior.h)");
  r->bind(s, "motion_prior_accel_m_s2", &accel_m_s2, 0.01, 1000.0, "m/s^2",
          "the vehicle's random acceleration, one standard deviation");
  r->bind(s, "motion_prior_angular_accel_rad_s2", &angular_accel_rad_s2, 0.01, 10000.0, "rad/s^2",
          "the vehicle's random angular acceleration, one standard deviation");
  r->bind(s, "motion_prior_max_speed_m_s", &max_speed_m_s, 0.01, 1000.0, "m/s",
          "the vehicle's top speed: the velocity's standard deviation when it is not known (first frame, "
          "relocalised), and the most that dead reckoning while lost takes");
  r->bind(s, "motion_prior_max_rate_rad_s", &max_rate_rad_s, 0.01, 1000.0, "rad/s",
          "the vehicle's top turn rate: the angular velocity's standard deviation when it is not known, and "
          "the most that dead reckoning while lost takes");
  r->bind(s, "motion_prior_in_final_fit", &in_final_fit,
          "the prior stays in the fit that gives the pose (false: it only chooses the matches, "
          "whose fit without it gives the pose)");
  r->bind(s, "motion_prior_min_gap_s", &min_gap_s, 0.0, 1.0, "s",
          "frames closer in time than this count as the same instant: no prior, the newer pose taken");
  r->bind(s, "motion_prior_max_gap_s", &max_gap_s, 0.001, 100.0, "s",
          "a longer time between two poses forgets the velocity");
}

std::optional<double> MotionPrior::gapS(int64_t utime) const {
  if (!options_.enabled || !have_pose_ || utime <= utime_) return std::nullopt;
  const double dt = static_cast<double>(utime - utime_) * 1e-6;
  if (dt > options_.max_gap_s || dt < options_.min_gap_s) return std::nullopt;
  return dt;
}

void MotionPrior::propagate(double dt, SE3* T, Vec6* v, Mat12* P) const {
  *T = SE3::exp(dt * v_) * T_c_w_;
  *v = v_;
  Mat12 F = Mat12::Identity();
  F.topRightCorner<6, 6>().diagonal().setConstant(dt);
  *P = F * P_ * F.transpose();
  const double dt2 = dt * dt;
  for (int i = 0; i < 6; ++i) {
    const double sigma = i < 3 ? options_.accel_m_s2 : options_.angular_accel_rad_s2;
    const double s2 = sigma * sigma;
    (*P)(i, i) += s2 * dt2 * dt2 / 4.0;
    (*P)(i, i + 6) += s2 * dt2 * dt / 2.0;
    (*P)(i + 6, i) += s2 * dt2 * dt / 2.0;
    (*P)(i + 6, i + 6) += s2 * dt2;
  }
}

std::optional<PosePrior> MotionPrior::predict(int64_t utime) const {
  const std::optional<double> dt = gapS(utime);
  if (!dt) return std::nullopt;
  PosePrior prior;
  Vec6 v;
  Mat12 P;
  propagate(*dt, &prior.T_c_w, &v, &P);
  prior.information = inverseSpd(P.topLeftCorner<6, 6>());
  if (!positiveDefinite(prior.information)) return std::nullopt;
  return prior;
}

void MotionPrior::update(int64_t utime, const SE3& T_c_w, const Mat6& measured_raw) {
  if (options_.enabled && have_pose_ && utime > utime_ && static_cast<double>(utime - utime_) * 1e-6 < options_.min_gap_s) {
    T_c_w_ = T_c_w;  // the same instant: the newer pose, the velocity as it was
    utime_ = utime;
    return;
  }
  const std::optional<double> dt = gapS(utime);
  if (!dt) {
    reset(utime, T_c_w, measured_raw);
    return;
  }
  const Mat6 measured = clampPsd(measured_raw);
  SE3 T_pred;
  Vec6 v_pred;
  Mat12 P;
  propagate(*dt, &T_pred, &v_pred, &P);
  const Mat6 P_TT = P.topLeftCorner<6, 6>();
  const Mat6 P_vT = P.bottomLeftCorner<6, 6>();
  const Mat6 K = P_vT * inverseSpd(P_TT);
  const Mat6 P_TT_post = inverseSpd(inverseSpd(P_TT) + measured);
  const Vec6 innovation = (T_c_w * T_pred.inverse()).log();
  Mat12 P_post;
  P_post.topLeftCorner<6, 6>() = P_TT_post;
  P_post.bottomLeftCorner<6, 6>() = K * P_TT_post;
  P_post.topRightCorner<6, 6>() = P_post.bottomLeftCorner<6, 6>().transpose();
  P_post.bottomRightCorner<6, 6>() = P.bottomRightCorner<6, 6>() - K * P_vT.transpose() + K * P_TT_post * K.transpose();
  P_post = 0.5 * (P_post + P_post.transpose()).eval();
  if (!P_post.allFinite() || !innovation.allFinite() || !positiveDefinite(P_post.topLeftCorner<6, 6>())) {
    reset(utime, T_c_w, measured);
    return;
  }
  v_ = v_pred + K * innovation;
  P_ = P_post;
  T_c_w_ = T_c_w;
  utime_ = utime;
}

void MotionPrior::reset(int64_t utime, const SE3& T_c_w, const Mat6& measured) {
  have_pose_ = true;
  utime_ = utime;
  T_c_w_ = T_c_w;
  v_.setZero();
  P_.setZero();
  const Mat6 information = clampPsd(measured) + kStartInformation * Mat6::Identity();
  P_.topLeftCorner<6, 6>() = inverseSpd(information);
  for (int i = 0; i < 6; ++i) {
    const double sigma = i < 3 ? options_.max_speed_m_s : options_.max_rate_rad_s;
    P_(i + 6, i + 6) = sigma * sigma;
  }
}

}  // namespace rgbdslam
