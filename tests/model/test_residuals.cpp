// Residuals of bundle adjustment: values, validity, and every analytic Jacobian against
// central numeric differentiation (the pose perturbed on the left, T_c_w <- exp(xi) T_c_w).
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "rgbdslam/model/residuals.h"

namespace rgbdslam {
namespace {

constexpr double kStep = 1e-6;         // central-difference step [m or rad]
constexpr double kRelativeTol = 1e-5;  // allowed |analytic - numeric| / max(1, |numeric|)

PinholeCamera pinholeCamera() { return PinholeCamera{}; }  // 525 px, no distortion

PinholeCamera freiburg1Camera() {
  PinholeCamera c;  // freiburg1's strong distortion
  c.fx = 517.306, c.fy = 516.469, c.cx = 318.643, c.cy = 255.314;
  c.k1 = 0.2624, c.k2 = -0.9531, c.p1 = -0.0054, c.p2 = 0.0026, c.k3 = 1.1633;
  return c;
}

struct Sample {
  SE3 T_c_w;
  Vec3 p_w;
};

// Random poses (translations within +-2 m, rotations up to ~1 rad) and points in front of
// the camera inside the field of view.
std::vector<Sample> randomSamples(int n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> depth(0.5, 5.0);
  std::vector<Sample> samples;
  for (int i = 0; i < n; ++i) {
    Vec6 xi;
    xi << 2 * unit(rng), 2 * unit(rng), 2 * unit(rng), 0.6 * unit(rng), 0.6 * unit(rng),
        0.6 * unit(rng);
    const SE3 T_w_c = SE3::exp(xi);
    const double z = depth(rng);
    const Vec3 p_c(0.5 * z * unit(rng), 0.4 * z * unit(rng), z);
    samples.push_back({T_w_c.inverse(), T_w_c * p_c});
  }
  return samples;
}

template <int R, int C>
double relativeError(const Eigen::Matrix<double, R, C>& analytic,
                     const Eigen::Matrix<double, R, C>& numeric) {
  return (analytic - numeric).norm() / std::max(1.0, numeric.norm());
}

// d f / d xi at xi = 0 of xi -> f(exp(xi) * T_c_w), f returning an R-vector.
template <int R, typename F>
Eigen::Matrix<double, R, 6> numericDxi(const F& f, const SE3& T_c_w) {
  Eigen::Matrix<double, R, 6> J;
  for (int k = 0; k < 6; ++k) {
    Vec6 delta = Vec6::Zero();
    delta[k] = kStep;
    J.col(k) = (f(SE3::exp(delta) * T_c_w) - f(SE3::exp(-delta) * T_c_w)) / (2 * kStep);
  }
  return J;
}

// d f / d p_w, f returning an R-vector.
template <int R, typename F>
Eigen::Matrix<double, R, 3> numericDpw(const F& f, const Vec3& p_w) {
  Eigen::Matrix<double, R, 3> J;
  for (int k = 0; k < 3; ++k) {
    Vec3 delta = Vec3::Zero();
    delta[k] = kStep;
    J.col(k) = (f(p_w + delta) - f(p_w - delta)) / (2 * kStep);
  }
  return J;
}

Eigen::Vector2d reprojection(const PinholeCamera& camera, const SE3& T_c_w, const Vec3& p_w,
                             const Eigen::Vector2d& uv) {
  Eigen::Vector2d e;
  EXPECT_TRUE(reprojectionResidual(camera, T_c_w, p_w, uv, &e));
  return e;
}

Eigen::Matrix<double, 1, 1> depthError(const SE3& T_c_w, const Vec3& p_w, double d) {
  Eigen::Matrix<double, 1, 1> e;
  EXPECT_TRUE(depthResidual(T_c_w, p_w, d, &e(0)));
  return e;
}

void checkReprojectionJacobians(const PinholeCamera& camera, uint32_t seed) {
  for (const Sample& s : randomSamples(25, seed)) {
    const Eigen::Vector2d uv(300.0, 200.0);  // any measurement: the Jacobian does not depend on it
    Eigen::Vector2d e;
    Eigen::Matrix<double, 2, 6> d_res_d_xi;
    Eigen::Matrix<double, 2, 3> d_res_d_pw;
    ASSERT_TRUE(reprojectionResidual(camera, s.T_c_w, s.p_w, uv, &e, &d_res_d_xi, &d_res_d_pw));
    const auto numeric_xi =
        numericDxi<2>([&](const SE3& T) { return reprojection(camera, T, s.p_w, uv); }, s.T_c_w);
    const auto numeric_pw =
        numericDpw<2>([&](const Vec3& p) { return reprojection(camera, s.T_c_w, p, uv); }, s.p_w);
    EXPECT_LT(relativeError(d_res_d_xi, numeric_xi), kRelativeTol) << "analytic\n"
                                                                   << d_res_d_xi << "\nnumeric\n"
                                                                   << numeric_xi;
    EXPECT_LT(relativeError(d_res_d_pw, numeric_pw), kRelativeTol) << "analytic\n"
                                                                   << d_res_d_pw << "\nnumeric\n"
                                                                   << numeric_pw;
  }
}

TEST(BaResiduals, ReprojectionJacobiansMatchNumericWithoutDistortion) {
  checkReprojectionJacobians(pinholeCamera(), 1);
}

TEST(BaResiduals, ReprojectionJacobiansMatchNumericWithFreiburg1Distortion) {
  checkReprojectionJacobians(freiburg1Camera(), 2);
}

TEST(BaResiduals, DepthJacobiansMatchNumeric) {
  for (const Sample& s : randomSamples(25, 3)) {
    const double d = 2.5;
    double e = 0.0;
    Eigen::Matrix<double, 1, 6> d_res_d_xi;
    Eigen::Matrix<double, 1, 3> d_res_d_pw;
    ASSERT_TRUE(depthResidual(s.T_c_w, s.p_w, d, &e, &d_res_d_xi, &d_res_d_pw));
    const auto numeric_xi =
        numericDxi<1>([&](const SE3& T) { return depthError(T, s.p_w, d); }, s.T_c_w);
    const auto numeric_pw =
        numericDpw<1>([&](const Vec3& p) { return depthError(s.T_c_w, p, d); }, s.p_w);
    EXPECT_LT(relativeError(d_res_d_xi, numeric_xi), kRelativeTol)
        << "analytic " << d_res_d_xi << "\nnumeric  " << numeric_xi;
    EXPECT_LT(relativeError(d_res_d_pw, numeric_pw), kRelativeTol)
        << "analytic " << d_res_d_pw << "\nnumeric  " << numeric_pw;
  }
}

// The check has teeth: the Jacobian of the other perturbation convention (right, T exp(xi))
// and a sign slip in the rotation columns both fail it.
TEST(BaResiduals, NumericCheckRejectsWrongConventions) {
  const PinholeCamera camera = freiburg1Camera();
  const Sample s = randomSamples(1, 4).front();
  const Eigen::Vector2d uv(300.0, 200.0);
  Eigen::Vector2d e;
  Eigen::Matrix<double, 2, 6> d_res_d_xi;
  ASSERT_TRUE(reprojectionResidual(camera, s.T_c_w, s.p_w, uv, &e, &d_res_d_xi));
  const auto left =
      numericDxi<2>([&](const SE3& T) { return reprojection(camera, T, s.p_w, uv); }, s.T_c_w);
  Eigen::Matrix<double, 2, 6> right;  // xi -> res(T_c_w * exp(xi))
  for (int k = 0; k < 6; ++k) {
    Vec6 delta = Vec6::Zero();
    delta[k] = kStep;
    right.col(k) = (reprojection(camera, s.T_c_w * SE3::exp(delta), s.p_w, uv) -
                    reprojection(camera, s.T_c_w * SE3::exp(-delta), s.p_w, uv)) /
                   (2 * kStep);
  }
  EXPECT_GT(relativeError(d_res_d_xi, right), 100 * kRelativeTol);
  Eigen::Matrix<double, 2, 6> flipped = d_res_d_xi;
  flipped.rightCols<3>() *= -1.0;
  EXPECT_GT(relativeError(flipped, left), 100 * kRelativeTol);
}

TEST(BaResiduals, ResidualsAreMeasuredMinusPredicted) {
  const PinholeCamera camera = freiburg1Camera();
  const Sample s = randomSamples(1, 5).front();
  const Vec3 p_c = s.T_c_w * s.p_w;
  const Eigen::Vector2d predicted = *camera.project(p_c);
  Eigen::Vector2d e;
  ASSERT_TRUE(
      reprojectionResidual(camera, s.T_c_w, s.p_w, predicted + Eigen::Vector2d(1.0, -2.0), &e));
  EXPECT_NEAR(e.x(), 1.0, 1e-9);
  EXPECT_NEAR(e.y(), -2.0, 1e-9);
  double e_d = 0.0;
  ASSERT_TRUE(depthResidual(s.T_c_w, s.p_w, p_c.z() + 0.1, &e_d));
  EXPECT_NEAR(e_d, 0.1, 1e-12);
}

TEST(BaResiduals, PointsBehindTheCameraAreInvalid) {
  const SE3 T_c_w;  // identity
  Eigen::Vector2d e;
  double e_d = 0.0;
  for (const Vec3& p_w : {Vec3(0.1, 0.2, -1.0), Vec3(0.0, 0.0, 0.0), Vec3(0.3, 0.1, 1e-4)}) {
    EXPECT_FALSE(reprojectionResidual(freiburg1Camera(), T_c_w, p_w, {320, 240}, &e))
        << p_w.transpose();
    EXPECT_FALSE(depthResidual(T_c_w, p_w, 1.0, &e_d)) << p_w.transpose();
  }
  EXPECT_TRUE(reprojectionResidual(freiburg1Camera(), T_c_w, Vec3(0, 0, 0.5), {320, 240}, &e));
  EXPECT_TRUE(depthResidual(T_c_w, Vec3(0, 0, 0.5), 1.0, &e_d));
}

}  // namespace
}  // namespace rgbdslam
