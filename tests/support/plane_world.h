#pragma once
// A world of infinite planes for tests of depth alone (depth alignment, dead reckoning):
// exact depth images rendered from any pose.
#include <cmath>
#include <vector>

#include <opencv2/core.hpp>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/geometry/se3.h"
#include "rgbdslam/image/rgbd_frame.h"

namespace rgbdslam {

inline PinholeCamera kinectCamera() {
  PinholeCamera camera;
  camera.width = 640;
  camera.height = 480;
  camera.fx = camera.fy = 525.0;
  camera.cx = 319.5;
  camera.cy = 239.5;
  return camera;
}

// The plane n . X = d in the world.
struct Plane {
  Vec3 n;
  double d;
};

// Exact metric depth (CV_32FC1) of the nearest plane along each pixel's ray, NaN where none.
inline cv::Mat renderDepth(const std::vector<Plane>& planes, const SE3& T_w_c, const PinholeCamera& camera) {
  cv::Mat depth(camera.height, camera.width, CV_32FC1, cv::Scalar(NAN));
  const Mat3 R = T_w_c.rotationMatrix();
  const Vec3 o = T_w_c.translation();
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const Vec3 ray = R * camera.unproject(Eigen::Vector2d(u, v), 1.0);  // camera z = 1
      double best = INFINITY;
      for (const Plane& p : planes) {
        const double t = (p.d - p.n.dot(o)) / p.n.dot(ray);
        if (t > 0.05 && t < best) best = t;
      }
      if (std::isfinite(best)) depth.at<float>(v, u) = static_cast<float>(best);
    }
  }
  return depth;
}

// A frame with that depth (raw, 0.2 mm units) and a plain grey image.
inline RgbdFrame frameWithDepth(const cv::Mat& depth_m) {
  RgbdFrame frame;
  frame.colour = cv::Mat(depth_m.size(), CV_8UC3, cv::Scalar(128, 128, 128));
  frame.depth_scale = 5000.0;
  depth_m.convertTo(frame.depth, CV_16UC1, frame.depth_scale);  // NaN becomes 0
  return frame;
}

}  // namespace rgbdslam
