#pragma once
// The residuals of bundle adjustment and of the tracker's pose fit (paper sec. IV): the 2-D reprojection error and the 1-D depth
// error of one measurement of map point p_w in one keyframe, with analytic Jacobians
// (eq. 6-10, 13-15). Their noise (sec. V, eq. 16, 17) is noise_model.h.
//
// Shape (the same for both, as in basalt's ba_utils.h): return false when the residual is not
// defined (point at or behind the camera); otherwise write the residual and, when the pointers
// are non-null, its Jacobians. Nothing here knows about Ceres; the solver adapters live in
// bundle_adjuster.h.
//
// Frames and perturbation: the keyframe pose is stored as T_w_c; these functions take its
// inverse T_c_w (the paper's T(A)), p_c = T_c_w * p_w. The pose Jacobians are with respect to
// the left perturbation of the inverse pose, T_c_w <- exp(xi) * T_c_w with xi = (v, w) in R^6
// as in SE3::exp, so d(p_c)/d(xi) = [I3 | -[p_c]x] at xi = 0 (eq. 10) and
// d(p_c)/d(p_w) = R_c_w (eq. 9).
//
// Units: pixels at pyramid level 0 for the 2-D residual, metres for the depth residual. The
// residuals are "measured minus predicted" (eq. 2), hence the minus signs in the Jacobians.
#include <Eigen/Core>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/geometry/se3.h"

namespace rgbdslam {

// e = uv_measured - c(h(T_c_w * p_w)) [px]. Jacobians:
//   d_res_d_xi = -d_uv_d_pc * [I3 | -[p_c]x]   (2x6)
//   d_res_d_pw = -d_uv_d_pc * R_c_w            (2x3)
// where d_uv_d_pc includes the lens distortion. False if p_c.z <= kMinBaPointDepth.
bool reprojectionResidual(const PinholeCamera& camera, const SE3& T_c_w, const Vec3& p_w,
                          const Eigen::Vector2d& uv_measured, Eigen::Vector2d* residual,
                          Eigen::Matrix<double, 2, 6>* d_res_d_xi = nullptr,
                          Eigen::Matrix<double, 2, 3>* d_res_d_pw = nullptr);

// e_d = depth_measured - (T_c_w * p_w)_z [m] (eq. 15). Jacobians are minus the last rows of
// eq. 13 and 14:
//   d_res_d_xi = -(0, 0, 1, p_c.y, -p_c.x, 0)  (1x6)
//   d_res_d_pw = -R_c_w.row(2)                 (1x3)
// False if p_c.z <= kMinBaPointDepth (the depth of a point behind the camera means nothing).
bool depthResidual(const SE3& T_c_w, const Vec3& p_w, double depth_measured, double* residual,
                   Eigen::Matrix<double, 1, 6>* d_res_d_xi = nullptr,
                   Eigen::Matrix<double, 1, 3>* d_res_d_pw = nullptr);

// Points closer to the camera than this [m] give no residual: the projection blows up and
// no RGB-D sensor measures there.
constexpr double kMinBaPointDepth = 1e-3;

}  // namespace rgbdslam
