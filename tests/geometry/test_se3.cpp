#include "rgbdslam/geometry/se3.h"

#include <gtest/gtest.h>

namespace rgbdslam {
namespace {

Vec6 makeXi(double a, double b, double c, double d, double e, double f) {
  Vec6 xi;
  xi << a, b, c, d, e, f;
  return xi;
}

TEST(SE3, ExpLogRoundTrip) {
  for (const Vec6& xi : {makeXi(0.1, -0.2, 0.3, 0.4, -0.5, 0.6), makeXi(1, 2, 3, 1e-9, 0, 2e-9),
                         makeXi(0, 0, 0, 0, 0, 0), makeXi(-1, 0.5, 0, 0, 3.0, 0)}) {
    EXPECT_LT((SE3::exp(xi).log() - xi).norm(), 1e-9) << xi.transpose();
  }
}

TEST(SE3, InverseComposesToIdentity) {
  const SE3 T = SE3::exp(makeXi(0.3, -1.0, 2.0, 0.2, 0.1, -0.7));
  EXPECT_LT((T * T.inverse()).log().norm(), 1e-12);
  EXPECT_LT((T.inverse() * T).log().norm(), 1e-12);
}

TEST(SE3, ActionMatchesMatrix) {
  const SE3 T = SE3::exp(makeXi(0.3, -1.0, 2.0, 0.2, 0.1, -0.7));
  const Vec3 p(1.0, 2.0, 3.0);
  const Eigen::Vector4d ph = T.matrix() * p.homogeneous();
  EXPECT_LT((T * p - ph.head<3>()).norm(), 1e-12);
}

TEST(SE3, ExpOfSmallRotationMatchesFirstOrder) {
  const Vec3 w(1e-7, -2e-7, 3e-7);
  const Mat3 R = expSO3(w);
  EXPECT_LT((R - (Mat3::Identity() + skew(w))).norm(), 1e-12);
  EXPECT_LT((logSO3(R) - w).norm(), 1e-15);
}

}  // namespace
}  // namespace rgbdslam
