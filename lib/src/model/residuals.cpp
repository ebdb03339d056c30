#include "rgbdslam/model/residuals.h"

#include <cmath>

namespace rgbdslam {

bool reprojectionResidual(const PinholeCamera& camera, const SE3& T_c_w, const Vec3& p_w,
                          const Eigen::Vector2d& uv_measured, Eigen::Vector2d* residual,
                          Eigen::Matrix<double, 2, 6>* d_res_d_xi,
                          Eigen::Matrix<double, 2, 3>* d_res_d_pw) {
  const Vec3 p_c = T_c_w * p_w;
  if (!(p_c.z() > kMinBaPointDepth)) return false;
  const bool want_jacobians = d_res_d_xi != nullptr || d_res_d_pw != nullptr;
  Eigen::Matrix<double, 2, 3> d_uv_d_pc;
  const auto uv = camera.project(p_c, want_jacobians ? &d_uv_d_pc : nullptr);
  if (!uv) return false;
  *residual = uv_measured - *uv;
  if (d_res_d_xi) {
    // d(p_c)/d(xi) = [I3 | -[p_c]x] (eq. 10), and the residual is measured minus predicted.
    d_res_d_xi->leftCols<3>() = -d_uv_d_pc;
    d_res_d_xi->rightCols<3>() = d_uv_d_pc * skew(p_c);
  }
  if (d_res_d_pw) *d_res_d_pw = -d_uv_d_pc * T_c_w.rotationMatrix();
  return true;
}

bool depthResidual(const SE3& T_c_w, const Vec3& p_w, double depth_measured, double* residual,
                   Eigen::Matrix<double, 1, 6>* d_res_d_xi,
                   Eigen::Matrix<double, 1, 3>* d_res_d_pw) {
  const Vec3 p_c = T_c_w * p_w;
  if (!(p_c.z() > kMinBaPointDepth)) return false;
  *residual = depth_measured - p_c.z();
  if (d_res_d_xi) {
    // Minus the last row of [I3 | -[p_c]x]: -[p_c]x has last row (p_c.y, -p_c.x, 0).
    *d_res_d_xi << 0.0, 0.0, -1.0, -p_c.y(), p_c.x(), 0.0;
  }
  if (d_res_d_pw) *d_res_d_pw = -T_c_w.rotationMatrix().row(2);
  return true;
}

}  // namespace rgbdslam
