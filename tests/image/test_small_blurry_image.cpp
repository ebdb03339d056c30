#include "rgbdslam/image/small_blurry_image.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace rgbdslam {
namespace {

constexpr double kDegree = M_PI / 180.0;

// A 1280x960 scene texture with blobs of a few tens of pixels, which survive the 1/16
// reduction; views of it are 640x480 crops.
cv::Mat sceneTexture(int seed) {
  cv::Mat noise(960, 1280, CV_32FC1);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), 12.0);
  cv::Mat image;
  cv::normalize(noise, noise, 20, 235, cv::NORM_MINMAX);
  noise.convertTo(image, CV_8UC1);
  return image;
}

// The 640x480 view of the scene whose content is moved by the Se2 (given in SBI px) from
// the centred crop: the scene point seen at pixel x of the centred crop is seen at
// R (x - c) + c + 16 t, c the image centre. New content at the edges is real scene.
cv::Mat view(const cv::Mat& scene, const Se2& se2) {
  const double c_x = 319.5, c_y = 239.5;  // image centre [px]
  const double o_x = (scene.cols - 640) / 2.0, o_y = (scene.rows - 480) / 2.0;  // crop origin
  const double cs = std::cos(se2.theta), sn = std::sin(se2.theta);
  const double scale = 1 << kSbiLevel;
  // view = R (scene - o - c) + c + 16 t
  const cv::Mat M = (cv::Mat_<double>(2, 3) << cs, -sn,
                     c_x + scale * se2.tx - (cs * (o_x + c_x) - sn * (o_y + c_y)), sn, cs,
                     c_y + scale * se2.ty - (sn * (o_x + c_x) + cs * (o_y + c_y)));
  cv::Mat image;
  cv::warpAffine(scene, image, M, cv::Size(640, 480), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  return image;
}

cv::Mat coarseTexture(int seed) { return view(sceneTexture(seed), Se2{}); }

SmallBlurryImage sbiOf(const cv::Mat& grey) { return makeSmallBlurryImage(buildPyramid(grey)); }

TEST(SmallBlurryImage, IsSixteenthSizeBlurredAndZeroMean) {
  const cv::Mat grey = coarseTexture(1);
  const SmallBlurryImage sbi = sbiOf(grey);
  EXPECT_EQ(sbi.image.size(), cv::Size(40, 30));
  EXPECT_EQ(sbi.image.type(), CV_32FC1);
  EXPECT_DOUBLE_EQ(sbi.scale, 1.0 / 16.0);
  EXPECT_NEAR(cv::mean(sbi.image)[0], 0.0, 1e-3);
  double min_value, max_value;
  cv::minMaxLoc(sbi.image, &min_value, &max_value);
  EXPECT_GT(max_value - min_value, 10.0);  // texture survives
  // Central differences.
  EXPECT_NEAR(sbi.grad_x.at<float>(10, 20), 0.5f * (sbi.image.at<float>(10, 21) - sbi.image.at<float>(10, 19)), 1e-4f);
  EXPECT_NEAR(sbi.grad_y.at<float>(10, 20), 0.5f * (sbi.image.at<float>(11, 20) - sbi.image.at<float>(9, 20)), 1e-4f);
  // Blurred: neighbouring SBI pixels differ far less than unblurred 1/16 pixels would.
  cv::Mat dx;
  cv::absdiff(sbi.image.colRange(1, 40), sbi.image.colRange(0, 39), dx);
  EXPECT_LT(cv::mean(dx)[0], 0.2 * (max_value - min_value));
  // A shallower pyramid gives the same SBI (the coarsest level is halved further).
  const SmallBlurryImage shallow = makeSmallBlurryImage(buildPyramid(grey, 2));
  EXPECT_EQ(cv::norm(shallow.image, sbi.image, cv::NORM_INF), 0.0);
}

// A keyframe keeps its SBI compact (its image only); restored, it is the SBI made.
TEST(SmallBlurryImage, ACompactSbiRestoresExactly) {
  const SmallBlurryImage made = sbiOf(coarseTexture(7));
  SmallBlurryImage sbi = made;
  sbi.grad_x = made.grad_x.clone(), sbi.grad_y = made.grad_y.clone(), sbi.support = made.support.clone();
  compactSmallBlurryImage(&sbi);
  EXPECT_FALSE(sbi.complete());
  EXPECT_TRUE(sbi.grad_x.empty() && sbi.grad_y.empty() && sbi.support.empty());
  restoreSmallBlurryImage(&sbi);
  ASSERT_TRUE(sbi.complete());
  for (const auto& [restored, original] : {std::pair{sbi.grad_x, made.grad_x}, {sbi.grad_y, made.grad_y},
                                          {sbi.support, made.support}}) {
    ASSERT_EQ(restored.size(), original.size());
    EXPECT_EQ(cv::norm(restored, original, cv::NORM_INF), 0.0);
  }
}

TEST(SmallBlurryImage, ZmssdComparesStructureNotBrightness) {
  const cv::Mat grey = coarseTexture(2);
  const SmallBlurryImage a = sbiOf(grey);
  const SmallBlurryImage brighter = sbiOf(grey + 15);
  const SmallBlurryImage other = sbiOf(coarseTexture(3));
  EXPECT_DOUBLE_EQ(zmssd(a, a), 0.0);
  EXPECT_LT(zmssd(a, brighter), 1e-3 * zmssd(a, other));
  SmallBlurryImage shifted = a;
  shifted.image = a.image + 5.0f;  // zmssd removes the means itself
  EXPECT_NEAR(zmssd(a, shifted), 0.0, 1e-3);
  EXPECT_GT(zmssd(a, other), 1000.0);
}

TEST(SmallBlurryImage, AlignmentRecoversRotationAndTranslation) {
  for (int seed : {4, 5}) {
    const cv::Mat scene = sceneTexture(seed);
    const SmallBlurryImage from = sbiOf(view(scene, Se2{}));
    for (const Se2& truth : {Se2{4.0 * kDegree, 1.5, -1.0}, Se2{-3.0 * kDegree, -1.0, 2.0},
                             Se2{0.0, 0.6, 0.3}, Se2{6.0 * kDegree, 0.0, 0.0},
                             Se2{8.0 * kDegree, 2.0, 2.0}}) {
      const SmallBlurryImage to = sbiOf(view(scene, truth));
      double error = -1;
      const Se2 estimate = alignSmallBlurryImages(from, to, kSbiAlignIterations, &error);
      EXPECT_NEAR(estimate.theta, truth.theta, 0.5 * kDegree);
      EXPECT_NEAR(estimate.tx, truth.tx, 0.3);
      EXPECT_NEAR(estimate.ty, truth.ty, 0.3);
      EXPECT_LT(error, 0.1 * zmssd(from, to) / (40 * 30)) << "residual did not shrink";
    }
  }
}

TEST(SmallBlurryImage, AlignmentOfIdenticalImagesIsIdentity) {
  const SmallBlurryImage sbi = sbiOf(coarseTexture(5));
  double error = -1;
  const Se2 estimate = alignSmallBlurryImages(sbi, sbi, kSbiAlignIterations, &error);
  EXPECT_NEAR(estimate.theta, 0.0, 1e-6);
  EXPECT_NEAR(estimate.tx, 0.0, 1e-6);
  EXPECT_NEAR(estimate.ty, 0.0, 1e-6);
  EXPECT_NEAR(error, 0.0, 1e-6);
}

// The relocaliser's coarse stage: halved SBIs (a compact one as a complete one) align to
// the same warp as the full ones, within a fraction of a full-resolution pixel.
TEST(SmallBlurryImage, HalvedSbisAlignToTheFullResolutionsWarp) {
  const cv::Mat scene = sceneTexture(4);
  SmallBlurryImage from = sbiOf(view(scene, Se2{}));
  const SmallBlurryImage complete_half = halveSmallBlurryImage(from);
  compactSmallBlurryImage(&from);
  const SmallBlurryImage half_from = halveSmallBlurryImage(from);
  ASSERT_EQ(half_from.image.size(), cv::Size(20, 15));
  ASSERT_TRUE(half_from.complete());
  EXPECT_DOUBLE_EQ(half_from.scale, 1.0 / 32.0);
  EXPECT_EQ(cv::norm(half_from.support, complete_half.support, cv::NORM_INF), 0.0);
  for (const Se2& truth : {Se2{4.0 * kDegree, 1.5, -1.0}, Se2{-3.0 * kDegree, -1.0, 2.0},
                           Se2{8.0 * kDegree, 2.0, 2.0}}) {
    const SmallBlurryImage to = sbiOf(view(scene, truth));
    const Se2 estimate =
        fullResolutionSe2(alignSmallBlurryImages(half_from, halveSmallBlurryImage(to)), to.image.size());
    EXPECT_NEAR(estimate.theta, truth.theta, 1.0 * kDegree);
    EXPECT_NEAR(estimate.tx, truth.tx, 0.5);
    EXPECT_NEAR(estimate.ty, truth.ty, 0.5);
  }
}

// Halving averages 2 x 2 blocks from the top left, an odd last row and column left out: on
// ramps, half pixel x_h holds the value of full pixel 2 x_h + 0.5.
TEST(SmallBlurryImage, HalvingAveragesTwoByTwoBlocks) {
  for (const bool along_x : {true, false}) {
    SmallBlurryImage ramp;
    ramp.image.create(31, 41, CV_32FC1);
    for (int y = 0; y < 31; ++y) {
      for (int x = 0; x < 41; ++x) ramp.image.at<float>(y, x) = static_cast<float>(along_x ? x : y);
    }
    const SmallBlurryImage half = halveSmallBlurryImage(ramp);  // compact: its support made
    ASSERT_EQ(half.image.size(), cv::Size(20, 15));
    ASSERT_TRUE(half.complete());
    for (const auto& [x_h, y_h] : {std::pair{0, 0}, {19, 14}, {7, 11}}) {
      EXPECT_FLOAT_EQ(half.image.at<float>(y_h, x_h), static_cast<float>(2 * (along_x ? x_h : y_h)) + 0.5f);
    }
    EXPECT_FLOAT_EQ(half.grad_x.at<float>(7, 10), along_x ? 2.0f : 0.0f);  // 2 full px per half px
  }
  SmallBlurryImage tiny;
  tiny.image = cv::Mat::zeros(1, 40, CV_32FC1);
  EXPECT_TRUE(halveSmallBlurryImage(tiny).image.empty());
}

// Started at the warp found coarsely, the alignment needs one step to reach what ten
// iterations from the identity reach; one step from the identity does not.
TEST(SmallBlurryImage, AlignmentStartedNearTheWarpConvergesAtOnce) {
  const cv::Mat scene = sceneTexture(5);
  const SmallBlurryImage from = sbiOf(view(scene, Se2{}));
  const SmallBlurryImage to = sbiOf(view(scene, Se2{8.0 * kDegree, 2.0, -1.5}));
  const Se2 full = alignSmallBlurryImages(from, to);
  const Se2 near = alignSmallBlurryImages(from, to, 1, nullptr, Se2{7.5 * kDegree, 1.8, -1.3});
  const Se2 far = alignSmallBlurryImages(from, to, 1);
  EXPECT_NEAR(near.theta, full.theta, 0.05 * kDegree);
  EXPECT_NEAR(near.tx, full.tx, 0.02);
  EXPECT_NEAR(near.ty, full.ty, 0.02);
  EXPECT_GT(std::abs(far.theta - full.theta) + std::abs(far.tx - full.tx), 0.05 * kDegree + 0.02)
      << "one step from the identity should not be enough";
}

// A warp between halved SBIs moves a half pixel x_h where its full-resolution warp moves the
// full pixel 2 x_h + 0.5, for even and odd sizes.
TEST(SmallBlurryImage, AHalfResolutionWarpScalesToTheFullImage) {
  const Se2 half{0.3, 1.25, -0.75};
  const auto warp = [](const Se2& se2, cv::Size size, const Eigen::Vector2d& x) {
    const Eigen::Vector2d c(0.5 * (size.width - 1), 0.5 * (size.height - 1));
    Eigen::Matrix2d R;
    R << std::cos(se2.theta), -std::sin(se2.theta), std::sin(se2.theta), std::cos(se2.theta);
    return (R * (x - c) + c + Eigen::Vector2d(se2.tx, se2.ty)).eval();
  };
  for (const cv::Size full : {cv::Size(40, 30), cv::Size(41, 31), cv::Size(20, 15)}) {
    const cv::Size size_h(full.width / 2, full.height / 2);
    const Se2 scaled = fullResolutionSe2(half, full);
    EXPECT_EQ(scaled.theta, half.theta);
    for (const Eigen::Vector2d& x_h : {Eigen::Vector2d(0, 0), Eigen::Vector2d(7, 3), Eigen::Vector2d(12.5, 9)}) {
      const Eigen::Vector2d expected = (2.0 * warp(half, size_h, x_h).array() + 0.5).matrix();
      const Eigen::Vector2d got = warp(scaled, full, (2.0 * x_h.array() + 0.5).matrix());
      EXPECT_LT((got - expected).norm(), 1e-9) << full.width << "x" << full.height;
    }
  }
}

// Rotation angle of a rotation matrix [rad].
double angleOf(const Mat3& R) { return logSO3(R).norm(); }

TEST(SmallBlurryImage, InPlaneRotationIsARollOfTheCamera) {
  PinholeCamera camera;  // 640x480, principal point at the image centre
  // Image content turns by +theta (x towards y): the new camera rolled by -theta about z.
  const SE3 T_old_new = rotationFromSe2(Se2{0.05, 0.0, 0.0}, camera, 1.0 / 16);
  const Mat3 expected = expSO3(Vec3(0, 0, -0.05));
  EXPECT_LT(angleOf(expected.transpose() * T_old_new.rotationMatrix()), 1e-9);
  EXPECT_EQ(T_old_new.translation(), Vec3::Zero());
}

TEST(SmallBlurryImage, ImageShiftIsAPanOfTheCamera) {
  PinholeCamera camera;
  const double tx = 1.0;  // [SBI px]: content moves right by 16 full-res px
  const SE3 T_old_new = rotationFromSe2(Se2{0.0, tx, 0.0}, camera, 1.0 / 16);
  // A point straight ahead moves right when the camera turns left (about -y, y down). A
  // pan moves off-centre points further than central ones, so the rotation fitted to a
  // uniform shift over the image is a few percent smaller than the centre's atan(16 tx / f).
  const Vec3 w = logSO3(T_old_new.rotationMatrix());
  EXPECT_NEAR(w.y(), -std::atan(16.0 * tx / camera.fx), 0.1 * std::abs(w.y()));
  EXPECT_NEAR(w.x(), 0.0, 1e-6);
  EXPECT_NEAR(w.z(), 0.0, 1e-6);
  // The sign convention directly: the bearing of the old image centre, seen from the new
  // camera (d_new = R_old_new^T d_old), projects about 16 px right of the new centre.
  const Vec3 d_new = T_old_new.rotationMatrix().transpose() * Vec3(0, 0, 1);
  const auto uv = camera.project(d_new);
  ASSERT_TRUE(uv);
  EXPECT_NEAR(uv->x(), camera.cx + 16.0 * tx, 1.5);
  EXPECT_NEAR(uv->y(), camera.cy, 1e-6);
}

TEST(SmallBlurryImage, RotationFromTheInducedImageMotionRoundTrips) {
  PinholeCamera camera;
  const double scale = 1.0 / 16;
  for (const Vec3& w_true : {Vec3(0.01, -0.02, 0.03), Vec3(-0.015, 0.0, -0.02), Vec3(0.0, 0.02, 0.0)}) {
    const Mat3 R_old_new = expSO3(w_true);
    // Image motion of a grid of SBI pixels under the camera rotation, then the best 2-D
    // rigid fit (Procrustes) to it.
    std::vector<Eigen::Vector2d> from, to;
    for (double v = 5; v <= 25; v += 5) {
      for (double u = 5; u <= 35; u += 5) {
        const Eigen::Vector2d uv_0 = (Eigen::Vector2d(u, v).array() + 0.5) / scale - 0.5;
        const Vec3 d_new = R_old_new.transpose() * camera.unproject(uv_0, 1.0);
        const auto uv_new = camera.project(d_new);
        ASSERT_TRUE(uv_new);
        from.emplace_back(u, v);
        to.push_back((uv_new->array() + 0.5) * scale - 0.5);
      }
    }
    const Eigen::Vector2d c(19.5, 14.5);
    Eigen::Vector2d mean_from = Eigen::Vector2d::Zero(), mean_to = Eigen::Vector2d::Zero();
    for (size_t i = 0; i < from.size(); ++i) mean_from += from[i] / from.size(), mean_to += to[i] / to.size();
    double s_cos = 0, s_sin = 0;
    for (size_t i = 0; i < from.size(); ++i) {
      const Eigen::Vector2d a = from[i] - mean_from, b = to[i] - mean_to;
      s_cos += a.dot(b);
      s_sin += a.x() * b.y() - a.y() * b.x();
    }
    Se2 se2;
    se2.theta = std::atan2(s_sin, s_cos);
    Eigen::Matrix2d R2;
    R2 << std::cos(se2.theta), -std::sin(se2.theta), std::sin(se2.theta), std::cos(se2.theta);
    const Eigen::Vector2d t = mean_to - c - R2 * (mean_from - c);
    se2.tx = t.x();
    se2.ty = t.y();
    const SE3 T_old_new = rotationFromSe2(se2, camera, scale);
    EXPECT_LT(angleOf(R_old_new.transpose() * T_old_new.rotationMatrix()), 0.05 * kDegree)
        << "w_true " << w_true.transpose() << " got " << logSO3(T_old_new.rotationMatrix()).transpose();
  }
}

}  // namespace
}  // namespace rgbdslam
