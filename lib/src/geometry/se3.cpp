#include "rgbdslam/geometry/se3.h"

#include <cmath>

namespace rgbdslam {
namespace {
constexpr double kSmallAngle = 1e-10;  // [rad^2] below this, Taylor expansions are used

// V(w) = I + (1-cos t)/t^2 w^ + (t - sin t)/t^3 w^2, the left Jacobian of SO(3).
Mat3 leftJacobianSO3(const Vec3& w) {
  const double theta2 = w.squaredNorm();
  const Mat3 W = skew(w);
  if (theta2 < kSmallAngle) return Mat3::Identity() + 0.5 * W + W * W / 6.0;
  const double theta = std::sqrt(theta2);
  return Mat3::Identity() + (1.0 - std::cos(theta)) / theta2 * W +
         (theta - std::sin(theta)) / (theta2 * theta) * W * W;
}
}  // namespace

Mat3 skew(const Vec3& w) {
  Mat3 W;
  W << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return W;
}

Mat3 expSO3(const Vec3& w) {
  const double theta = w.norm();
  if (theta * theta < kSmallAngle) {
    return Eigen::Quaterniond(1.0, 0.5 * w.x(), 0.5 * w.y(), 0.5 * w.z()).normalized().toRotationMatrix();
  }
  return Eigen::AngleAxisd(theta, w / theta).toRotationMatrix();
}

Vec3 logSO3(const Mat3& R) {
  const Eigen::AngleAxisd aa(R);
  double angle = aa.angle();
  Vec3 axis = aa.axis();
  if (angle > M_PI) {  // keep the angle in [0, pi]
    angle = 2.0 * M_PI - angle;
    axis = -axis;
  }
  return angle * axis;
}

Eigen::Matrix4d SE3::matrix() const {
  Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
  M.topLeftCorner<3, 3>() = rotationMatrix();
  M.topRightCorner<3, 1>() = t_;
  return M;
}

SE3 SE3::inverse() const {
  const Eigen::Quaterniond q_inv = q_.conjugate();
  return SE3(q_inv, -(q_inv * t_));
}

SE3 SE3::operator*(const SE3& other) const { return SE3(q_ * other.q_, q_ * other.t_ + t_); }

SE3 SE3::exp(const Vec6& xi) {
  const Vec3 v = xi.head<3>();
  const Vec3 w = xi.tail<3>();
  return SE3(expSO3(w), leftJacobianSO3(w) * v);
}

Vec6 SE3::log() const {
  const Vec3 w = logSO3(rotationMatrix());
  Vec6 xi;
  xi.head<3>() = leftJacobianSO3(w).inverse() * t_;
  xi.tail<3>() = w;
  return xi;
}

}  // namespace rgbdslam
