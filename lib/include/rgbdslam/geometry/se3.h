#pragma once
// Rigid-body transforms. Naming: T_a_b maps coordinates in frame b into frame a
// (p_a = T_a_b * p_b). Tangent vectors xi = (v, w): translation part first, then rotation,
// with exp(xi) = [exp(w^) V(w) v; 0 1], as in PTAM's SE3 and Sophus.
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rgbdslam {

using Vec3 = Eigen::Vector3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat3 = Eigen::Matrix3d;

class SE3 {
 public:
  SE3() : q_(Eigen::Quaterniond::Identity()), t_(Vec3::Zero()) {}
  SE3(const Eigen::Quaterniond& q, const Vec3& t) : q_(q.normalized()), t_(t) {}
  SE3(const Mat3& R, const Vec3& t) : q_(Eigen::Quaterniond(R).normalized()), t_(t) {}

  const Eigen::Quaterniond& rotation() const { return q_; }
  Mat3 rotationMatrix() const { return q_.toRotationMatrix(); }
  const Vec3& translation() const { return t_; }
  Eigen::Matrix4d matrix() const;

  SE3 inverse() const;
  SE3 operator*(const SE3& other) const;
  Vec3 operator*(const Vec3& p) const { return q_ * p + t_; }

  static SE3 exp(const Vec6& xi);
  Vec6 log() const;

 private:
  Eigen::Quaterniond q_;
  Vec3 t_;
};

Mat3 skew(const Vec3& w);
// Rodrigues: exp and log of SO(3), numerically safe near the identity.
Mat3 expSO3(const Vec3& w);
Vec3 logSO3(const Mat3& R);

}  // namespace rgbdslam
