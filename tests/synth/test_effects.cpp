// The sensor effects of the synthetic renderer (SensorEffects in synth/scene.h) and the
// office scene: each effect measured against its stated model.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "rgbdslam/synth/scene.h"

namespace rgbdslam {
namespace {

SyntheticOptions parsedSpec(const std::string& spec) {
  const auto options = parseSyntheticSpec(spec);
  EXPECT_TRUE(options.ok()) << (options.ok() ? "" : options.error());
  return options.ok() ? *options : SyntheticOptions{};
}

// A camera at p_w looking along yaw (0: +x, pi/2: +y) and pitch (up positive), no roll.
SE3 lookingAlong(const Vec3& p_w, double yaw, double pitch = 0) {
  const Vec3 forward(std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw),
                     std::sin(pitch));
  const Vec3 right(std::sin(yaw), -std::cos(yaw), 0.0);
  Mat3 R_w_c;
  R_w_c.col(0) = right;
  R_w_c.col(1) = forward.cross(right);
  R_w_c.col(2) = forward;
  return SE3(R_w_c, p_w);
}

// Angle between pixel (u, v)'s ray and the normal of a wall of constant world 'axis'.
double incidenceOnWall(const SE3& T_w_c, const PinholeCamera& cam, int u, int v, int axis) {
  const Vec3 d_w = T_w_c.rotationMatrix() * Vec3((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1);
  return std::acos(std::abs(d_w[axis]) / d_w.norm());
}

double nguyenSigma(double z, double theta) {
  const double r = theta / (M_PI / 2 - theta);
  return 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4) + 0.0001 / std::sqrt(z) * r * r;
}

double gradientEnergy(const cv::Mat& grey) {
  cv::Mat gx, gy;
  cv::Sobel(grey, gx, CV_32F, 1, 0);
  cv::Sobel(grey, gy, CV_32F, 0, 1);
  return cv::mean(gx.mul(gx) + gy.mul(gy))[0];
}

// Shi-Tomasi corners: local maxima of the smaller structure-tensor eigenvalue above an
// absolute threshold (well above what image noise of sigma 2 gives).
int shiTomasiCorners(const cv::Mat& grey) {
  cv::Mat eig, dilated;
  cv::cornerMinEigenVal(grey, eig, 5, 3);
  cv::dilate(eig, dilated, cv::Mat());
  const cv::Mat peaks = (eig >= dilated) & (eig > 0.005f);
  return cv::countNonZero(peaks);
}

// ---- spec

TEST(SyntheticEffects, KeysRoundTripAndDefaultOff) {
  const SyntheticOptions room = parsedSpec("room");
  EXPECT_FALSE(room.effects.any());
  EXPECT_EQ(formatSyntheticSpec(room), "room");
  const SyntheticOptions all = parsedSpec("corridor,effects=all");
  EXPECT_TRUE(all.effects == SensorEffects::all());
  EXPECT_EQ(formatSyntheticSpec(all), "corridor,effects=all");
  const std::string spec =
      "room,exposure=12.5,auto_exposure=0.3,vignetting=0.4,shot_noise=0.1,depth_noise=nguyen,"
      "edge_holes=2,ir_shadow=1,dark_holes=0.03,shiny_holes=1";
  const SyntheticOptions each = parsedSpec(spec);
  EXPECT_DOUBLE_EQ(each.effects.exposure_ms, 12.5);
  EXPECT_DOUBLE_EQ(each.effects.auto_exposure_s, 0.3);
  EXPECT_DOUBLE_EQ(each.effects.vignetting, 0.4);
  EXPECT_DOUBLE_EQ(each.effects.shot_noise, 0.1);
  EXPECT_TRUE(each.effects.nguyen_depth);
  EXPECT_EQ(each.effects.edge_holes_px, 2);
  EXPECT_TRUE(each.effects.ir_shadow);
  EXPECT_DOUBLE_EQ(each.effects.dark_holes, 0.03);
  EXPECT_TRUE(each.effects.shiny_holes);
  EXPECT_EQ(formatSyntheticSpec(each), spec);
  EXPECT_EQ(formatSyntheticSpec(parsedSpec("room,effects=all,exposure=0")),
            "room,auto_exposure=0.5,vignetting=0.5,shot_noise=0.05,"
            "depth_noise=nguyen,edge_holes=1,ir_shadow=1,dark_holes=0.01,shiny_holes=1");
  // The office has every effect on unless told otherwise.
  EXPECT_TRUE(parsedSpec("office").effects == SensorEffects::all());
  EXPECT_EQ(formatSyntheticSpec(parsedSpec("office")), "office");
  EXPECT_EQ(formatSyntheticSpec(parsedSpec("office,effects=none")), "office,effects=none");
  const SyntheticOptions office_some = parsedSpec("office,vignetting=0,ir_shadow=0");
  EXPECT_EQ(formatSyntheticSpec(parsedSpec(formatSyntheticSpec(office_some))),
            formatSyntheticSpec(office_some));
  EXPECT_DOUBLE_EQ(office_some.effects.vignetting, 0.0);
  EXPECT_FALSE(office_some.effects.ir_shadow);
  EXPECT_TRUE(office_some.effects.nguyen_depth);
}

TEST(SyntheticEffects, BadValuesNameTheKey) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"room,effects=some", "effects"},       {"room,exposure=-1", "exposure"},
      {"room,exposure=40", "exposure"},       {"room,rate=60,exposure=20", "exposure"},
      {"room,exposure=long", "exposure"},     {"room,auto_exposure=11", "auto_exposure"},
      {"room,auto_exposure=-0.1", "auto_exposure"}, {"room,vignetting=1.5", "vignetting"},
      {"room,shot_noise=-0.1", "shot_noise"}, {"room,shot_noise=20", "shot_noise"},
      {"room,depth_noise=gauss", "depth_noise"}, {"room,edge_holes=1.5", "edge_holes"},
      {"room,edge_holes=11", "edge_holes"},   {"room,ir_shadow=yes", "ir_shadow"},
      {"room,dark_holes=2", "dark_holes"},    {"room,shiny_holes=2", "shiny_holes"},
      {"office,colour=1", "colour"},
  };
  for (const auto& [spec, named] : cases) {
    const auto result = parseSyntheticSpec(spec);
    ASSERT_FALSE(result.ok()) << "accepted '" << spec << "'";
    EXPECT_NE(result.error().find(named), std::string::npos)
        << "error for '" << spec << "' does not name '" << named << "': " << result.error();
  }
}

TEST(SyntheticEffects, AllEffectsAreDeterministicInAnyOrder) {
  const SyntheticScene scene(parsedSpec("room,frames=60,effects=all"));
  const RgbdFrame late = scene.render(40);
  const RgbdFrame early = scene.render(3);
  const RgbdFrame again = SyntheticScene(parsedSpec("room,frames=60,effects=all")).render(40);
  EXPECT_EQ(cv::norm(late.colour, again.colour, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(late.depth, again.depth, cv::NORM_INF), 0);
  EXPECT_GT(cv::norm(late.colour, early.colour, cv::NORM_L1), 0);
  // And they change the frames.
  const RgbdFrame plain = SyntheticScene(parsedSpec("room,frames=60")).render(40);
  EXPECT_GT(cv::norm(late.colour, plain.colour, cv::NORM_L1), 0);
  EXPECT_GT(cv::norm(late.depth, plain.depth, cv::NORM_L1), 0);
}

// ---- image

// Mean image motion [px] of the scene points of frame i from frame i to frame i + 1 (depth
// from a noise-free render, a grid of pixels).
double imageMotionPx(const SyntheticScene& scene, size_t i) {
  const PinholeCamera& cam = scene.camera();
  const cv::Mat z = scene.render(i).depthMetres();
  const SE3 T_next_this = scene.groundTruthPose(i + 1).inverse() * scene.groundTruthPose(i);
  double sum = 0;
  int count = 0;
  for (int v = 10; v < z.rows; v += 20) {
    for (int u = 10; u < z.cols; u += 20) {
      const float d = z.at<float>(v, u);
      if (std::isnan(d)) continue;
      const Vec3 p = T_next_this * (d * Vec3((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1));
      sum += std::hypot(cam.fx * p.x() / p.z() + cam.cx - u, cam.fy * p.y() / p.z() + cam.cy - v);
      ++count;
    }
  }
  return sum / count;
}

TEST(SyntheticEffects, MotionBlurLowersGradientEnergyWithTheMotion) {
  // The room's frame 100 moves fast in the image, frame 200 slowly; longer exposures smear
  // more.
  const SyntheticScene sharp(parsedSpec("room,noise_sigma=0"));
  std::vector<double> energy;
  for (const double exposure_ms : {0.0, 8.0, 16.0, 33.0}) {
    const std::string spec = "room,noise_sigma=0,exposure=" + std::to_string(exposure_ms);
    energy.push_back(gradientEnergy(SyntheticScene(parsedSpec(spec)).render(100).grey()));
  }
  for (size_t k = 1; k < energy.size(); ++k) {
    EXPECT_LT(energy[k], energy[k - 1]) << "exposure step " << k;
  }
  EXPECT_LT(energy[3], 0.7 * energy[0]);
  // The loss grows with the motion: twice the exposure loses more than once.
  EXPECT_GT(energy[0] - energy[2], 1.5 * (energy[0] - energy[1]));
  // And a frame that moves less in the image loses less.
  const SyntheticScene blurred(parsedSpec("room,noise_sigma=0,exposure=33"));
  const double loss_fast = 1 - energy[3] / energy[0];
  const double loss_slow =
      1 - gradientEnergy(blurred.render(200).grey()) / gradientEnergy(sharp.render(200).grey());
  ASSERT_GT(imageMotionPx(sharp, 100), 1.5 * imageMotionPx(sharp, 200));
  EXPECT_GT(loss_fast, 2 * loss_slow) << "fast " << loss_fast << " slow " << loss_slow;
}

TEST(SyntheticEffects, VignettingDarkensCornersByTheCos4Law) {
  const SE3 pose = lookingAlong(Vec3(3.0, 2.5, 1.5), 0.0);
  const SyntheticScene flat(parsedSpec("room,noise_sigma=0"));
  const SyntheticScene full(parsedSpec("room,noise_sigma=0,vignetting=1"));
  const SyntheticScene half(parsedSpec("room,noise_sigma=0,vignetting=0.5"));
  const cv::Mat a = flat.renderPose(pose, 0).grey(), b = full.renderPose(pose, 0).grey();
  const cv::Mat c = half.renderPose(pose, 0).grey();
  const PinholeCamera& cam = flat.camera();
  const cv::Rect corner(0, 0, 12, 12), centre(314, 234, 12, 12);
  const double tan2 = (std::pow(6 - cam.cx, 2) + std::pow(6 - cam.cy, 2)) / (cam.fx * cam.fx);
  const double cos4 = 1.0 / ((1 + tan2) * (1 + tan2));
  const double corner_ratio = cv::mean(b(corner))[0] / cv::mean(a(corner))[0];
  EXPECT_NEAR(corner_ratio, cos4, 0.03) << "cos^4 = " << cos4;
  EXPECT_NEAR(cv::mean(c(corner))[0] / cv::mean(a(corner))[0], 1 - 0.5 * (1 - cos4), 0.03);
  EXPECT_NEAR(cv::mean(b(centre))[0] / cv::mean(a(centre))[0], 1.0, 0.01);
}

TEST(SyntheticEffects, AutoExposureGainLagsTheMeteredGain) {
  const double tau = 0.5;
  const SyntheticScene scene(parsedSpec("office,effects=none,auto_exposure=0.5"));
  const double rate = scene.options().rate_hz;
  // An independent first-order lag in log gain, from frame 0's target.
  const double decay = std::exp(-1.0 / (rate * tau));
  double log_lag = std::log(scene.meteredGain(0)), max_gap = 0;
  for (size_t i = 0; i < 1240; i += 1) {
    const double target = scene.meteredGain(i);
    log_lag = decay * log_lag + (1 - decay) * std::log(target);
    if (i % 10 != 0) continue;
    const double gain = scene.exposureGain(i);
    // The window of 4 tau leaves out e^-4 of the weight: well under 0.5 % here.
    EXPECT_NEAR(gain / std::exp(log_lag), 1.0, 0.005) << "frame " << i;
    max_gap = std::max(max_gap, std::abs(std::log(gain / target)));
  }
  EXPECT_GT(max_gap, 0.02) << "the gain should lag behind a changing target";
  // The image is the clean one times the gain (where not clamped at 255).
  const RgbdFrame off = SyntheticScene(parsedSpec("office,effects=none,noise_sigma=0")).render(150);
  const RgbdFrame on =
      SyntheticScene(parsedSpec("office,effects=none,noise_sigma=0,auto_exposure=0.5")).render(150);
  const cv::Mat unclamped = off.grey() < 200 / std::max(1.0, scene.exposureGain(150));
  EXPECT_NEAR(cv::mean(on.grey(), unclamped)[0] / cv::mean(off.grey(), unclamped)[0],
              scene.exposureGain(150), 0.02);
  EXPECT_DOUBLE_EQ(SyntheticScene(parsedSpec("office,effects=none")).exposureGain(150), 1.0);
}

TEST(SyntheticEffects, ShotNoiseGrowsWithTheSignal) {
  const SE3 pose = lookingAlong(Vec3(3.0, 2.5, 1.5), 0.0);
  const cv::Mat clean = SyntheticScene(parsedSpec("room,noise_sigma=0")).renderPose(pose, 0).colour;
  const cv::Mat noisy =
      SyntheticScene(parsedSpec("room,noise_sigma=2,shot_noise=0.5")).renderPose(pose, 0).colour;
  // Residual variance per grey level bin (of 32 levels, where there are enough pixels),
  // against 2^2 + 0.5 I.
  int bins_checked = 0;
  for (int lo = 0; lo < 256; lo += 32) {
    double sum_sq = 0;
    int count = 0;
    for (int v = 0; v < clean.rows; ++v) {
      for (int k = 0; k < clean.cols * 3; ++k) {
        const int i = clean.ptr<uint8_t>(v)[k];
        if (i < lo || i >= lo + 32) continue;
        const double r = noisy.ptr<uint8_t>(v)[k] - i;
        sum_sq += r * r, ++count;
      }
    }
    if (count < 20000) continue;
    ++bins_checked;
    const double expected = 4.0 + 0.5 * (lo + 15.5) + 1.0 / 12;  // + rounding to levels
    EXPECT_NEAR(sum_sq / count / expected, 1.0, 0.1) << "grey " << lo << "-" << lo + 31;
  }
  EXPECT_GE(bins_checked, 3);
}

// ---- depth

// Normalised depth error std over the central 200 x 200 pixels facing the room's east wall.
double frontalDepthStd(double distance_m) {
  const SyntheticScene truth(parsedSpec("room,depth_sigma=0,quantise=0,noise_sigma=0"));
  const SyntheticScene noisy(parsedSpec("room,depth_noise=nguyen,quantise=0,noise_sigma=0"));
  double sum_sq = 0;
  int count = 0;
  for (const size_t i : {0, 1, 2}) {
    const SE3 pose = lookingAlong(Vec3(6.0 - distance_m, 2.6, 1.6), 0.0);
    const cv::Mat exact = truth.renderPose(pose, i).depthMetres();
    const cv::Mat measured = noisy.renderPose(pose, i).depthMetres();
    for (int v = 140; v < 340; ++v) {
      for (int u = 220; u < 420; ++u) {
        const float z = exact.at<float>(v, u), z_n = measured.at<float>(v, u);
        if (std::isnan(z) || std::isnan(z_n) || std::abs(z - distance_m) > 1e-3) continue;
        const double r = (z_n - z) / nguyenSigma(z, incidenceOnWall(pose, truth.camera(), u, v, 0));
        sum_sq += r * r, ++count;
      }
    }
  }
  EXPECT_GT(count, 100000);
  return std::sqrt(sum_sq / count);
}

TEST(SyntheticEffects, FrontalDepthNoiseFollowsNguyenAt1And3Metres) {
  EXPECT_NEAR(frontalDepthStd(1.0), 1.0, 0.03);  // sigma 1.88 mm
  EXPECT_NEAR(frontalDepthStd(3.0), 1.0, 0.03);  // sigma 14.0 mm
}

// RMS of the depth error over pixels on the room's east wall (x = 6 m) at depth 1.5-2.5 m
// with incidence in [lo, hi) deg, normalised by the frontal Nguyen sigma at their depth.
double eastWallError(const SE3& pose, double lo_deg, double hi_deg, int* count) {
  const SyntheticScene truth(parsedSpec("room,depth_sigma=0,quantise=0,noise_sigma=0"));
  const SyntheticScene noisy(parsedSpec("room,depth_noise=nguyen,quantise=0,noise_sigma=0"));
  const cv::Mat exact = truth.renderPose(pose, 0).depthMetres();
  const cv::Mat measured = noisy.renderPose(pose, 0).depthMetres();
  double sum_sq = 0;
  *count = 0;
  for (int v = 0; v < exact.rows; ++v) {
    for (int u = 0; u < exact.cols; ++u) {
      const float z = exact.at<float>(v, u), z_n = measured.at<float>(v, u);
      if (std::isnan(z) || std::isnan(z_n) || z < 1.5f || z > 2.5f) continue;
      const Vec3 p_w = pose * (z * Vec3((u - 319.5) / 525.0, (v - 239.5) / 525.0, 1.0));
      if (std::abs(p_w.x() - 6.0) > 1e-3 || p_w.y() < 1.5 || p_w.z() < 1.3) continue;  // plain wall
      const double theta = incidenceOnWall(pose, truth.camera(), u, v, 0) * 180 / M_PI;
      if (theta < lo_deg || theta >= hi_deg) continue;
      const double r = (z_n - z) / nguyenSigma(z, 0);
      sum_sq += r * r, ++*count;
    }
  }
  return std::sqrt(sum_sq / std::max(1, *count));
}

TEST(SyntheticEffects, GrazingWallsAreNoisier) {
  int frontal_count = 0, grazing_count = 0;
  const double frontal =
      eastWallError(lookingAlong(Vec3(4.0, 2.6, 1.6), 0.0), 0, 20, &frontal_count);
  // 0.5 m from the wall, looking 70 deg off its normal: 70-80 deg incidence at 1.5-2.5 m.
  const double grazing =
      eastWallError(lookingAlong(Vec3(5.5, 1.6, 1.6), 70 * M_PI / 180), 70, 80, &grazing_count);
  ASSERT_GT(frontal_count, 2000);
  ASSERT_GT(grazing_count, 2000);
  EXPECT_NEAR(frontal, 1.0, 0.1);
  EXPECT_GT(grazing, 1.3 * frontal) << "frontal " << frontal << " grazing " << grazing;
}

// Row-wise depth edges of a clean frame (jump > 0.3 m): the far pixel beside each edge,
// split by side (the far surface left of a nearer one, or right of it), with the expected
// shadow width f b (1/z_near - 1/z_far) [px].
struct FarSideOfEdges {
  std::vector<std::pair<cv::Point, double>> left, right;
};
FarSideOfEdges farSides(const cv::Mat& z) {
  FarSideOfEdges sides;
  for (int v = 0; v < z.rows; ++v) {
    for (int u = 1; u < z.cols; ++u) {
      const float a = z.at<float>(v, u - 1), b = z.at<float>(v, u);
      if (std::isnan(a) || std::isnan(b) || std::abs(a - b) < 0.3f) continue;
      const double width = 525.0 * 0.075 * (1.0 / std::min(a, b) - 1.0 / std::max(a, b));
      if (a > b) sides.left.push_back({cv::Point(u - 1, v), width});
      else sides.right.push_back({cv::Point(u, v), width});
    }
  }
  return sides;
}

TEST(SyntheticEffects, IrShadowsLieLeftOfNearerEdgesOnly) {
  const SyntheticScene clean(parsedSpec("room,depth_sigma=0,quantise=0"));
  const SyntheticScene shadowed(parsedSpec("room,depth_sigma=0,quantise=0,ir_shadow=1"));
  int left_holes = 0, left_total = 0, right_holes = 0, right_total = 0;
  double band_error = 0;
  for (const size_t i : {100, 250, 400, 550}) {
    const cv::Mat z = clean.render(i).depthMetres(), zs = shadowed.render(i).depthMetres();
    const FarSideOfEdges sides = farSides(z);
    for (const auto& [p, width] : sides.left) {
      if (width < 2.0) continue;
      ++left_total;
      left_holes += std::isnan(zs.at<float>(p));
      int band = 0;  // the hole's width to the left of the edge
      while (p.x - band >= 0 && std::isnan(zs.at<float>(p.y, p.x - band)) &&
             !std::isnan(z.at<float>(p.y, p.x - band))) {
        ++band;
      }
      band_error += std::abs(band - width);
    }
    for (const auto& [p, width] : sides.right) {
      if (width < 2.0) continue;
      ++right_total;
      right_holes += std::isnan(zs.at<float>(p));
    }
  }
  ASSERT_GT(left_total, 100);
  ASSERT_GT(right_total, 100);
  EXPECT_GT(left_holes, 0.95 * left_total);
  EXPECT_LT(right_holes, 0.02 * right_total);
  EXPECT_LT(band_error / left_total, 1.0) << "mean |band - f b (1/z_near - 1/z_far)| [px]";
}

TEST(SyntheticEffects, EdgeHolesFollowDepthDiscontinuities) {
  const SyntheticScene clean(parsedSpec("room,depth_sigma=0,quantise=0"));
  const SyntheticScene holed(parsedSpec("room,depth_sigma=0,quantise=0,edge_holes=2"));
  const cv::Mat z = clean.render(250).depthMetres(), zh = holed.render(250).depthMetres();
  const FarSideOfEdges sides = farSides(z);
  int near_holes = 0, near_total = 0, far_kept = 0, far_total = 0;
  for (const int dir : {-1, 1}) {  // away from the edge on the far side
    for (const auto& [p, width] : dir < 0 ? sides.left : sides.right) {
      ++near_total;
      near_holes += std::isnan(zh.at<float>(p.y, p.x + dir));  // 2nd pixel of the band
      const int u = p.x + 6 * dir;
      if (u < 0 || u >= z.cols || std::isnan(z.at<float>(p.y, u))) continue;
      ++far_total;
      far_kept += !std::isnan(zh.at<float>(p.y, u));
    }
  }
  ASSERT_GT(near_total, 100);
  EXPECT_GT(near_holes, 0.95 * near_total);
  EXPECT_GT(far_kept, 0.8 * far_total);  // others edges may lie within 6 px
}

TEST(SyntheticEffects, DarkFarSurfacesLoseDepthBrightNearOnesKeepIt) {
  const SyntheticScene clean(parsedSpec("room,depth_sigma=0,quantise=0,noise_sigma=0"));
  const SyntheticScene lossy(parsedSpec("room,depth_sigma=0,quantise=0,noise_sigma=0,dark_holes=0.03"));
  int dark = 0, dark_lost = 0, bright = 0, bright_kept = 0;
  for (const size_t i : {0, 200, 400}) {
    const RgbdFrame a = clean.render(i), b = lossy.render(i);
    const cv::Mat z = a.depthMetres(), zl = b.depthMetres(), grey = a.grey();
    for (int v = 0; v < z.rows; v += 2) {
      for (int u = 0; u < z.cols; u += 2) {
        const float d = z.at<float>(v, u);
        if (std::isnan(d)) continue;
        const int g = grey.at<uint8_t>(v, u);
        // signal = g/255 cos / z^2: below 0.03 for g < 30 beyond 2 m whatever the angle;
        // at least 0.06 (always kept) for g > 120, z < 2 m and cos > 0.51 (most are).
        if (g < 30 && d > 2.0f) ++dark, dark_lost += std::isnan(zl.at<float>(v, u));
        if (g > 120 && d < 2.0f) ++bright, bright_kept += !std::isnan(zl.at<float>(v, u));
      }
    }
  }
  ASSERT_GT(dark, 200);
  ASSERT_GT(bright, 200);
  EXPECT_EQ(dark_lost, dark);
  EXPECT_GT(bright_kept, 0.8 * bright);
}

TEST(SyntheticEffects, ShinySurfacesLoseDepthFacingTheSensor) {
  // Facing the office's whiteboard (north wall of B, x in [7, 8.8], z in [0.9, 2]) from 1.5 m.
  const SE3 pose = lookingAlong(Vec3(7.9, 3.5, 1.45), M_PI / 2);
  const SyntheticScene kept(parsedSpec("office,effects=none"));
  const SyntheticScene lost(parsedSpec("office,effects=none,shiny_holes=1"));
  cv::Mat surfaces;
  const cv::Mat za = kept.renderPose(pose, 0, &surfaces).depthMetres();
  const cv::Mat zb = lost.renderPose(pose, 0).depthMetres();
  int facing = 0, facing_lost = 0, oblique = 0, oblique_kept = 0;
  for (int v = 0; v < za.rows; ++v) {
    for (int u = 0; u < za.cols; ++u) {
      if (surfaces.at<uint8_t>(v, u) != static_cast<int>(SyntheticSurface::kShiny)) continue;
      if (std::isnan(za.at<float>(v, u))) continue;  // without shiny_holes it has depth
      const double theta = incidenceOnWall(pose, kept.camera(), u, v, 1) * 180 / M_PI;
      if (theta < 10) ++facing, facing_lost += std::isnan(zb.at<float>(v, u));
      if (theta > 15 && theta < 60) ++oblique, oblique_kept += !std::isnan(zb.at<float>(v, u));
    }
  }
  ASSERT_GT(facing, 5000);
  ASSERT_GT(oblique, 5000);
  EXPECT_EQ(facing_lost, facing);
  EXPECT_EQ(oblique_kept, oblique);
}

// ---- the office

TEST(SyntheticOffice, HandHeldWalkOf5To9MillimetresPerFrameInsideTheRooms) {
  const SyntheticScene office(parsedSpec("office"));
  ASSERT_EQ(office.numFrames(), 1240u);
  double path = 0, max_rate = 0;
  for (size_t i = 0; i < office.numFrames(); ++i) {
    const Vec3 p = office.groundTruthPose(i).translation();
    EXPECT_TRUE(p.x() > 0.6 && p.x() < 10.2 - 0.6 && p.y() > 0.6 && p.y() < 5.0 - 0.6 &&
                p.z() > 1.2 && p.z() < 1.5)
        << "frame " << i << " at " << p.transpose();
    if (i == 0) continue;
    const SE3 step = office.groundTruthPose(i - 1).inverse() * office.groundTruthPose(i);
    const double mm = 1000 * step.translation().norm();
    EXPECT_TRUE(mm >= 5.0 && mm <= 9.0) << "frame " << i << ": " << mm << " mm";
    max_rate = std::max(max_rate, logSO3(step.rotationMatrix()).norm() * 30 * 180 / M_PI);
    path += step.translation().norm();
  }
  EXPECT_GT(path, 8.0);
  EXPECT_LT(max_rate, 45.0) << "deg/s";
}

TEST(SyntheticOffice, SurfacesStayBetweenHalfAMetreAndFourMetres) {
  const SyntheticScene office(parsedSpec("office,effects=none,depth_sigma=0,quantise=0"));
  for (size_t i = 0; i < office.numFrames(); i += 20) {
    const cv::Mat z = office.render(i).depthMetres();
    std::vector<float> depths;
    for (auto it = z.begin<float>(); it != z.end<float>(); ++it) {
      if (!std::isnan(*it)) depths.push_back(*it);
    }
    ASSERT_GT(depths.size(), z.total() / 2) << "frame " << i;
    std::nth_element(depths.begin(), depths.begin() + depths.size() / 10, depths.end());
    EXPECT_LT(depths[depths.size() / 10], 4.0f) << "frame " << i << ": nothing within 4 m";
    EXPECT_GE(*std::min_element(depths.begin(), depths.end()), 0.5f) << "frame " << i;
  }
}

TEST(SyntheticOffice, HasStretchesOfPlainWallsWithFewCorners) {
  const SyntheticScene office(parsedSpec("office"));
  const SyntheticScene room(parsedSpec("room"));
  int fewest_office = 1 << 30, fewest_room = 1 << 30, plain_frames = 0;
  for (size_t i = 0; i < office.numFrames(); i += 40) {
    const int corners = shiTomasiCorners(office.render(i).grey());
    fewest_office = std::min(fewest_office, corners);
    plain_frames += corners < 5;
  }
  for (size_t i = 0; i < room.numFrames(); i += 40) {
    fewest_room = std::min(fewest_room, shiTomasiCorners(room.render(i).grey()));
  }
  EXPECT_LT(fewest_office, 5);
  EXPECT_GE(plain_frames, 3) << "frames (of " << office.numFrames() / 40 + 1 << ") with < 5 corners";
  EXPECT_GT(fewest_room, 50);
  // Depth everywhere on the plain walls: most pixels have a reading.
  const RgbdFrame frame = office.render(800);
  EXPECT_GT(cv::countNonZero(frame.depth), frame.depth.total() * 7 / 10);
}

}  // namespace
}  // namespace rgbdslam
