#include "rgbdslam/camera/pinhole_camera.h"

#include <Eigen/LU>

namespace rgbdslam {
namespace {
constexpr double kMinDepth = 1e-6;          // [m] points closer than this do not project
constexpr int kUndistortIterations = 20;    // Gauss-Newton steps for undistortion
constexpr double kUndistortTolerance = 1e-12;  // [normalised units^2] convergence threshold
}  // namespace

Eigen::Vector2d PinholeCamera::distortAndScale(const Eigen::Vector2d& m,
                                               Eigen::Matrix2d* d_uv_d_m) const {
  const double x = m.x(), y = m.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const double xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
  const double yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
  if (d_uv_d_m) {
    const double d_radial_d_r2 = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);
    const double dxd_dx = radial + 2.0 * x * x * d_radial_d_r2 + 2.0 * p1 * y + 6.0 * p2 * x;
    const double dxd_dy = 2.0 * x * y * d_radial_d_r2 + 2.0 * p1 * x + 2.0 * p2 * y;
    const double dyd_dx = 2.0 * x * y * d_radial_d_r2 + 2.0 * p1 * x + 2.0 * p2 * y;
    const double dyd_dy = radial + 2.0 * y * y * d_radial_d_r2 + 6.0 * p1 * y + 2.0 * p2 * x;
    *d_uv_d_m << fx * dxd_dx, fx * dxd_dy, fy * dyd_dx, fy * dyd_dy;
  }
  return {fx * xd + cx, fy * yd + cy};
}

std::optional<Eigen::Vector2d> PinholeCamera::project(const Eigen::Vector3d& p_c,
                                                      Eigen::Matrix<double, 2, 3>* d_uv_d_pc) const {
  if (!(p_c.z() > kMinDepth)) return std::nullopt;
  const double inv_z = 1.0 / p_c.z();
  const Eigen::Vector2d m(p_c.x() * inv_z, p_c.y() * inv_z);
  if (!d_uv_d_pc) return distortAndScale(m);
  Eigen::Matrix2d d_uv_d_m;
  const Eigen::Vector2d uv = distortAndScale(m, &d_uv_d_m);
  Eigen::Matrix<double, 2, 3> d_m_d_pc;
  d_m_d_pc << inv_z, 0, -m.x() * inv_z, 0, inv_z, -m.y() * inv_z;
  *d_uv_d_pc = d_uv_d_m * d_m_d_pc;
  return uv;
}

Eigen::Vector2d PinholeCamera::unprojectToPlane(const Eigen::Vector2d& uv) const {
  Eigen::Vector2d m((uv.x() - cx) / fx, (uv.y() - cy) / fy);
  if (!hasDistortion()) return m;
  const Eigen::Vector2d target = uv;
  for (int i = 0; i < kUndistortIterations; ++i) {
    Eigen::Matrix2d J;
    const Eigen::Vector2d r = distortAndScale(m, &J) - target;
    const Eigen::Vector2d step = J.lu().solve(r);
    m -= step;
    if (step.squaredNorm() < kUndistortTolerance) break;
  }
  return m;
}

PinholeCamera PinholeCamera::scaled(double scale) const {
  PinholeCamera c = *this;
  c.width = static_cast<int>(width * scale);
  c.height = static_cast<int>(height * scale);
  c.fx = fx * scale;
  c.fy = fy * scale;
  // Pixel centres: (u + 0.5) * scale - 0.5.
  c.cx = (cx + 0.5) * scale - 0.5;
  c.cy = (cy + 0.5) * scale - 0.5;
  return c;
}

}  // namespace rgbdslam
