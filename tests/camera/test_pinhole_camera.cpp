#include "rgbdslam/camera/pinhole_camera.h"

#include <gtest/gtest.h>

namespace rgbdslam {
namespace {

PinholeCamera distortedCamera() {
  PinholeCamera c;  // freiburg1's strong distortion
  c.fx = 517.306, c.fy = 516.469, c.cx = 318.643, c.cy = 255.314;
  c.k1 = 0.2624, c.k2 = -0.9531, c.p1 = -0.0054, c.p2 = 0.0026, c.k3 = 1.1633;
  return c;
}

TEST(PinholeCamera, ProjectsCentreToPrincipalPoint) {
  const PinholeCamera c = distortedCamera();
  const auto uv = c.project(Eigen::Vector3d(0, 0, 2));
  ASSERT_TRUE(uv);
  EXPECT_NEAR(uv->x(), c.cx, 1e-12);
  EXPECT_NEAR(uv->y(), c.cy, 1e-12);
}

TEST(PinholeCamera, RejectsPointsBehind) {
  EXPECT_FALSE(distortedCamera().project(Eigen::Vector3d(0.1, 0.2, -1.0)));
  EXPECT_FALSE(distortedCamera().project(Eigen::Vector3d(0.1, 0.2, 0.0)));
}

TEST(PinholeCamera, UnprojectInvertsProjectOverTheImage) {
  const PinholeCamera c = distortedCamera();
  for (double u = 0; u < c.width; u += 40) {
    for (double v = 0; v < c.height; v += 40) {
      const Eigen::Vector3d p = c.unproject({u, v}, 1.7);
      const auto uv = c.project(p);
      ASSERT_TRUE(uv);
      EXPECT_LT((*uv - Eigen::Vector2d(u, v)).norm(), 1e-6) << u << "," << v;
      EXPECT_NEAR(p.z(), 1.7, 1e-12);
    }
  }
}

TEST(PinholeCamera, ProjectionJacobianMatchesNumeric) {
  const PinholeCamera c = distortedCamera();
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(0.3, -0.2, 1.5), Eigen::Vector3d(-0.6, 0.4, 1.1),
                                   Eigen::Vector3d(0.01, 0.02, 4.0)}) {
    Eigen::Matrix<double, 2, 3> analytic;
    ASSERT_TRUE(c.project(p, &analytic));
    const double h = 1e-6;
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d dp = Eigen::Vector3d::Zero();
      dp[k] = h;
      const Eigen::Vector2d numeric = (*c.project(p + dp) - *c.project(p - dp)) / (2 * h);
      EXPECT_LT((analytic.col(k) - numeric).norm(), 1e-4 * (1 + numeric.norm()))
          << "column " << k << " at " << p.transpose();
    }
  }
}

TEST(PinholeCamera, ScaledCameraMatchesHalvedImage) {
  PinholeCamera c;
  const PinholeCamera half = c.scaled(0.5);
  const Eigen::Vector3d p(0.2, -0.1, 2.0);
  const Eigen::Vector2d full = *c.project(p);
  const Eigen::Vector2d expected((full.x() + 0.5) * 0.5 - 0.5, (full.y() + 0.5) * 0.5 - 0.5);
  EXPECT_LT((*half.project(p) - expected).norm(), 1e-9);
  EXPECT_EQ(half.width, 320);
}

}  // namespace
}  // namespace rgbdslam
