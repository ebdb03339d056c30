#pragma once
// Pinhole camera with radial-tangential (Brown-Conrady, OpenCV order k1 k2 p1 p2 k3)
// distortion. Frames: p_c is a point in the camera frame (x right, y down, z forward) [m];
// pixels (u, v) with (0, 0) at the centre of the top-left pixel.
// Call order: project() maps p_c to a distorted pixel; unproject() inverts it iteratively.
#include <Eigen/Core>
#include <optional>
#include <string>

namespace rgbdslam {

struct PinholeCamera {
  std::string name;              // calibration name, e.g. "tum_fr3"
  int width = 640;               // [px]
  int height = 480;              // [px]
  double fx = 525.0;             // focal length [px]
  double fy = 525.0;             // focal length [px]
  double cx = 319.5;             // principal point [px]
  double cy = 239.5;             // principal point [px]
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;  // distortion coefficients (OpenCV order)
  double depth_factor = 5000.0;  // raw depth units per metre (TUM 5000, OpenNI mm 1000)

  bool hasDistortion() const { return k1 != 0 || k2 != 0 || p1 != 0 || p2 != 0 || k3 != 0; }
  bool inImage(const Eigen::Vector2d& uv, double border = 0.0) const {
    return uv.x() >= border && uv.y() >= border && uv.x() <= width - 1 - border &&
           uv.y() <= height - 1 - border;
  }

  // Normalised image coordinates m = (x/z, y/z) -> distorted pixel. Optional Jacobian
  // d_uv_d_m (2x2).
  Eigen::Vector2d distortAndScale(const Eigen::Vector2d& m,
                                  Eigen::Matrix2d* d_uv_d_m = nullptr) const;
  // Camera-frame point -> pixel; nullopt when the point is not in front of the camera
  // (z <= min_depth). Optional Jacobian d_uv_d_pc (2x3).
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& p_c,
                                         Eigen::Matrix<double, 2, 3>* d_uv_d_pc = nullptr) const;
  // Pixel -> normalised coordinates (x/z, y/z), undistorting by Gauss-Newton iterations.
  Eigen::Vector2d unprojectToPlane(const Eigen::Vector2d& uv) const;
  // Pixel and depth z [m] -> camera-frame point.
  Eigen::Vector3d unproject(const Eigen::Vector2d& uv, double z) const {
    const Eigen::Vector2d m = unprojectToPlane(uv);
    return Eigen::Vector3d(m.x() * z, m.y() * z, z);
  }
  // The same camera for an image scaled by 'scale' (e.g. 0.5 per pyramid level).
  PinholeCamera scaled(double scale) const;
};

}  // namespace rgbdslam
