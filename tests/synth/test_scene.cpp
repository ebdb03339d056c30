#include "rgbdslam/synth/scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "rgbdslam/camera/calibration_io.h"
#include "test_support.h"

namespace rgbdslam {
namespace {

SyntheticOptions noiseFree(SyntheticOptions options) {
  options.noise.sigma_coefficient = 0.0;
  options.noise.quantise = false;
  options.noise.image_noise_sigma = 0.0;
  return options;
}

SyntheticOptions parsed(const std::string& spec) {
  const auto options = parseSyntheticSpec(spec);
  EXPECT_TRUE(options.ok()) << (options.ok() ? "" : options.error());
  return options.ok() ? *options : SyntheticOptions{};
}

double depthAt(const RgbdFrame& frame, int u, int v) {
  return frame.depth.at<uint16_t>(v, u) / frame.depth_scale;
}

bool identical(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

// FAST-9 (the segment test of Rosten & Drummond, as cv::FAST with TYPE_9_16 and non-maximum
// suppression), written out here as an independent check of the corners the library finds.
const int kCircle[16][2] = {{0, -3}, {1, -3}, {2, -2}, {3, -1}, {3, 0},  {3, 1},
                            {2, 2},  {1, 3},  {0, 3},  {-1, 3}, {-2, 2}, {-3, 1},
                            {-3, 0}, {-3, -1}, {-2, -2}, {-1, -3}};

bool isFastCorner(const cv::Mat& grey, int u, int v, int threshold) {
  const int centre = grey.at<uint8_t>(v, u);
  for (const int sign : {1, -1}) {
    int run = 0;
    for (int k = 0; k < 16 + 9; ++k) {
      const int value = grey.at<uint8_t>(v + kCircle[k % 16][1], u + kCircle[k % 16][0]);
      run = sign * (value - centre) > threshold ? run + 1 : 0;
      if (run >= 9) return true;
    }
  }
  return false;
}

// The largest threshold at which the pixel is still a corner (cv::FAST's score).
int fastScore(const cv::Mat& grey, int u, int v, int threshold) {
  int lo = threshold, hi = 255;
  while (lo < hi) {
    const int mid = (lo + hi + 1) / 2;
    if (isFastCorner(grey, u, v, mid)) lo = mid; else hi = mid - 1;
  }
  return lo;
}

int countFastCorners(const cv::Mat& grey, int threshold) {
  cv::Mat score(grey.size(), CV_32SC1, cv::Scalar(0));
  for (int v = 3; v < grey.rows - 3; ++v) {
    for (int u = 3; u < grey.cols - 3; ++u) {
      if (isFastCorner(grey, u, v, threshold)) score.at<int>(v, u) = fastScore(grey, u, v, threshold);
    }
  }
  int count = 0;
  for (int v = 4; v < grey.rows - 4; ++v) {
    for (int u = 4; u < grey.cols - 4; ++u) {
      const int s = score.at<int>(v, u);
      if (s == 0) continue;
      bool is_max = true;
      for (int dv = -1; dv <= 1 && is_max; ++dv) {
        for (int du = -1; du <= 1; ++du) {
          if ((du || dv) && score.at<int>(v + dv, u + du) >= s) is_max = false;
        }
      }
      count += is_max;
    }
  }
  return count;
}

// ---- options and spec

TEST(SyntheticSpec, AcceptsGoodSpecs) {
  auto room = parseSyntheticSpec("room");
  ASSERT_TRUE(room.ok()) << room.error();
  EXPECT_EQ(room->scene, SyntheticSceneKind::kRoom);
  EXPECT_EQ(room->seed, 1u);

  auto spec = parseSyntheticSpec(
      "corridor, seed=3,frames=90,rate=15,depth_fraction=0.3,depth_frames=5,min_range=0.6,"
      "max_range=4,noise_sigma=0,depth_sigma=0.002,quantise=0");
  ASSERT_TRUE(spec.ok()) << spec.error();
  EXPECT_EQ(spec->scene, SyntheticSceneKind::kCorridor);
  EXPECT_EQ(spec->seed, 3u);
  EXPECT_EQ(spec->num_frames, 90);
  EXPECT_DOUBLE_EQ(spec->rate_hz, 15.0);
  EXPECT_DOUBLE_EQ(spec->noise.depth_fraction, 0.3);
  EXPECT_EQ(spec->noise.depth_frames, 5);
  EXPECT_DOUBLE_EQ(spec->noise.min_range_m, 0.6);
  EXPECT_DOUBLE_EQ(spec->noise.max_range_m, 4.0);
  EXPECT_DOUBLE_EQ(spec->noise.image_noise_sigma, 0.0);
  EXPECT_DOUBLE_EQ(spec->noise.sigma_coefficient, 0.002);
  EXPECT_FALSE(spec->noise.quantise);

  EXPECT_FALSE(parsed("room,depth=off").noise.depth_enabled);
  EXPECT_EQ(parsed("room,depth=first").noise.depth_frames, 1);
  EXPECT_TRUE(parsed("room,depth=off,depth=on").noise.depth_enabled);
}

TEST(SyntheticSpec, FormatRoundTrips) {
  const SyntheticOptions options = parsed("corridor,seed=7,depth_fraction=0.25,depth=off,rate=10");
  const std::string spec = formatSyntheticSpec(options);
  const SyntheticOptions again = parsed(spec);
  EXPECT_EQ(formatSyntheticSpec(again), spec);
  EXPECT_EQ(again.seed, 7u);
  EXPECT_DOUBLE_EQ(again.noise.depth_fraction, 0.25);
  EXPECT_FALSE(again.noise.depth_enabled);
  EXPECT_EQ(formatSyntheticSpec(SyntheticOptions{}), "room");
  EXPECT_EQ(formatSyntheticSpec(parsed("room,drop=120-149")), "room,drop=120-149");
  EXPECT_EQ(formatSyntheticSpec(parsed("room,drop=7")), "room,drop=7-7");
  EXPECT_EQ(formatSyntheticSpec(parsed("room,every=2,cover=5")), "room,every=2,cover=5-5");
  EXPECT_EQ(formatSyntheticSpec(parsed("room,distortion=0.25:-0.5:0.001:0")),
            "room,distortion=0.25:-0.5:0.001:0:0");
  EXPECT_EQ(formatSyntheticSpec(parsed("room,size=320x240,intrinsics=262.5:262.5:159.5:119.5")),
            "room,size=320x240,intrinsics=262.5:262.5:159.5:119.5");
  EXPECT_EQ(formatSyntheticSpec(parsed("flight,minutes=2,seed=4")), "flight,seed=4,minutes=2");
}

TEST(SyntheticSpec, RejectsBadSpecsNamingTheProblem) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"kitchen", "kitchen"},
      {"", "unknown scene"},
      {"room,colour=1", "colour"},
      {"room,seed=abc", "seed"},
      {"room,seed=-1", "seed"},
      {"room,frames=1.5", "frames"},
      {"room,rate=0", "rate"},
      {"room,rate=fast", "rate"},
      {"room,depth_fraction=0", "depth_fraction"},
      {"room,depth_fraction=1.5", "depth_fraction"},
      {"room,depth=maybe", "depth"},
      {"room,depth_frames=-2", "depth_frames"},
      {"room,min_range=5", "max_range"},
      {"room,max_range=20", "max_range"},
      {"room,noise_sigma=-1", "noise_sigma"},
      {"room,depth_sigma=x", "depth_sigma"},
      {"room,quantise=yes", "quantise"},
      {"room,seed", "seed"},
      {"room,drop=", "drop"},
      {"room,drop=a-b", "drop"},
      {"room,drop=-1", "drop"},
      {"room,drop=150-120", "drop"},
      {"room,drop=3-", "drop"},
      {"room,every=0", "every"},
      {"room,every=two", "every"},
      {"room,cover=9-3", "cover"},
      {"room,cover=x", "cover"},
      {"room,distortion=0.1:0.2", "distortion"},
      {"room,distortion=a:b:c:d", "distortion"},
      {"room,distortion=0:0:0:0:0:0", "distortion"},
      {"room,distortion=0.1:0:0:0:", "distortion"},
      {"room,distortion=-3:0:0:0", "distortion"},  // folds over: cannot be inverted
      {"room,size=640", "size"},
      {"room,size=10x10", "size"},
      {"room,intrinsics=500:500:320", "intrinsics"},
      {"room,intrinsics=0:500:320:240", "intrinsics"},
      {"room,size=320x240,intrinsics=300:300:319.5:239.5", "principal point"},
      {"flight,minutes=0.5,frames=100", "not both"},
      {"flight,minutes=-1", "minutes"},
      {"flight,minutes=1000", "minutes"},
      {"flight,minutes=ten", "minutes"},
  };
  for (const auto& [spec, named] : cases) {
    const auto result = parseSyntheticSpec(spec);
    ASSERT_FALSE(result.ok()) << "accepted '" << spec << "'";
    EXPECT_NE(result.error().find(named), std::string::npos)
        << "error for '" << spec << "' does not name '" << named << "': " << result.error();
  }
}

// ---- camera, time, trajectory

TEST(SyntheticScene, CameraMatchesConfigFile) {
  const std::string path = test::sourceDir() + "/config/cameras/synthetic.yaml";
  const auto loaded = loadCamera(path);
  ASSERT_TRUE(loaded.ok()) << loaded.error();
  const SyntheticScene scene(parsed("room,frames=1"));
  const PinholeCamera& camera = scene.camera();
  EXPECT_EQ(loaded->name, camera.name);
  EXPECT_EQ(loaded->name, "synthetic");
  EXPECT_EQ(loaded->width, 640);
  EXPECT_EQ(loaded->height, 480);
  EXPECT_EQ(loaded->width, camera.width);
  EXPECT_EQ(loaded->height, camera.height);
  EXPECT_DOUBLE_EQ(loaded->fx, camera.fx);
  EXPECT_DOUBLE_EQ(loaded->fy, camera.fy);
  EXPECT_DOUBLE_EQ(loaded->cx, camera.cx);
  EXPECT_DOUBLE_EQ(loaded->cy, camera.cy);
  EXPECT_FALSE(loaded->hasDistortion());
  EXPECT_FALSE(camera.hasDistortion());
  EXPECT_DOUBLE_EQ(loaded->depth_factor, camera.depth_factor);
  EXPECT_DOUBLE_EQ(loaded->depth_factor, 5000.0);
}

TEST(SyntheticScene, DefaultLengthsAndTimestamps) {
  const SyntheticScene room(parsed("room"));
  EXPECT_EQ(room.numFrames(), 600u);
  EXPECT_EQ(room.frameUtime(0), 1700000000LL * 1000000LL);
  EXPECT_EQ(room.frameUtime(30) - room.frameUtime(0), 1000000);
  EXPECT_EQ(room.frameUtime(1) - room.frameUtime(0), 33333);
  const Trajectory truth = room.groundTruth();
  ASSERT_EQ(truth.size(), 600u);
  EXPECT_DOUBLE_EQ(truth[10].t, room.frameUtime(10) * 1e-6);
  EXPECT_LT((truth[10].T_w_c.inverse() * room.groundTruthPose(10)).log().norm(), 1e-12);
  EXPECT_EQ(SyntheticScene(parsed("corridor")).numFrames(), 3300u);
  EXPECT_EQ(SyntheticScene(parsed("room,frames=7")).numFrames(), 7u);
  EXPECT_EQ(SyntheticScene(parsed("flight")).numFrames(), 18000u);  // ten minutes
  EXPECT_EQ(SyntheticScene(parsed("flight,minutes=2")).numFrames(), 3600u);
  EXPECT_EQ(SyntheticScene(parsed("twins")).numFrames(), 1800u);
  EXPECT_EQ(SyntheticScene(parsed("room,minutes=0.5,rate=20")).numFrames(), 600u);
}

TEST(SyntheticScene, RoomTrajectoryIsHandHeldInsideTheRoom) {
  const SyntheticScene room(parsed("room"));
  double max_speed = 0, max_rate = 0, path = 0;
  for (size_t i = 0; i < room.numFrames(); ++i) {
    const SE3 T = room.groundTruthPose(i);
    const Vec3& p = T.translation();
    EXPECT_TRUE(p.x() >= 0.8 && p.x() <= 6.0 - 0.8 && p.y() >= 0.8 && p.y() <= 5.0 - 0.8 &&
                p.z() >= 0.8 && p.z() <= 3.0 - 0.8)
        << "frame " << i << " at " << p.transpose();
    if (i == 0) continue;
    const SE3 step = room.groundTruthPose(i - 1).inverse() * T;
    const double dt = 1.0 / room.options().rate_hz;
    max_speed = std::max(max_speed, step.translation().norm() / dt);
    max_rate = std::max(max_rate, logSO3(step.rotationMatrix()).norm() / dt);
    path += step.translation().norm();
  }
  EXPECT_GT(max_speed, 0.2);
  EXPECT_LT(max_speed, 0.7);
  EXPECT_GT(max_rate * 180 / M_PI, 10.0);
  EXPECT_LT(max_rate * 180 / M_PI, 30.0);
  EXPECT_GT(path, 3.0);
}

TEST(SyntheticScene, CorridorTravelsAtLeast100Metres) {
  const SyntheticScene corridor(parsed("corridor"));
  double path = 0, max_speed = 0;
  for (size_t i = 1; i < corridor.numFrames(); ++i) {
    const double step = (corridor.groundTruthPose(i).translation() -
                         corridor.groundTruthPose(i - 1).translation()).norm();
    path += step;
    max_speed = std::max(max_speed, step * corridor.options().rate_hz);
  }
  EXPECT_GE(path, 100.0);
  EXPECT_LT(max_speed, 1.3);
  const double duration = (corridor.numFrames() - 1) / corridor.options().rate_hz;
  EXPECT_NEAR(path / duration, 1.0, 0.1);  // ~1 m/s
}

// The flight's free space (lib/src/synth/flight.cpp): rooms and corridors with their height
// and their open ends (a corridor end opens into a room or another corridor).
struct FreeSpace {
  double x0, y0, x1, y1, h;
  bool open_x0, open_x1, open_y0, open_y1;
};
const FreeSpace kFlightSpaces[] = {
    {0, 0, 8, 7, 3.0, false, false, false, false},      // A
    {8, 2.5, 20, 4.5, 2.6, true, true, false, false},   // C1
    {20, -1, 32, 11, 4.0, false, false, false, false},  // B
    {21, 11, 23, 16, 2.6, false, false, true, true},    // C2
    {12, 16, 24, 23, 3.0, false, false, false, false},  // C
    {3, 18, 12, 20, 2.6, false, true, false, false},    // C3a
    {3, 7, 5, 18, 2.6, false, false, true, true},       // C3b
};

// True if p keeps 'margin' from every wall, floor and ceiling of some space (an open end
// reaches 1 m through the doorway into the next space).
bool insideTheBuilding(const Vec3& p, double margin) {
  auto inset = [margin](bool open) { return open ? -1.0 : margin; };
  for (const FreeSpace& s : kFlightSpaces) {
    if (p.x() >= s.x0 + inset(s.open_x0) && p.x() <= s.x1 - inset(s.open_x1) &&
        p.y() >= s.y0 + inset(s.open_y0) && p.y() <= s.y1 - inset(s.open_y1) &&
        p.z() >= margin && p.z() <= s.h - margin) {
      return true;
    }
  }
  return false;
}

TEST(SyntheticScene, FlightIsATenMinuteTourOfRoomsAndCorridors) {
  const SyntheticScene flight(parsed("flight"));
  const double rate = flight.options().rate_hz;
  double path = 0, max_speed = 0, max_rate = 0, z_min = 1e9, z_max = -1e9;
  int hover_frames = 0, longest_hover = 0, fast_frames = 0, spin_frames = 0;
  int returns_to_start = 0;
  bool away = false;
  const Vec3 start = flight.groundTruthPose(0).translation();
  for (size_t i = 0; i < flight.numFrames(); ++i) {
    const SE3 T = flight.groundTruthPose(i);
    const Vec3& p = T.translation();
    ASSERT_TRUE(insideTheBuilding(p, 0.4)) << "frame " << i << " at " << p.transpose();
    z_min = std::min(z_min, p.z()), z_max = std::max(z_max, p.z());
    const double from_start = (p - start).head<2>().norm();
    if (from_start > 10) away = true;
    if (away && from_start < 3) returns_to_start += 1, away = false;
    if (i == 0) continue;
    const SE3 step = flight.groundTruthPose(i - 1).inverse() * T;
    const double speed = step.translation().norm() * rate;
    const double turn_rate = logSO3(step.rotationMatrix()).norm() * rate * 180 / M_PI;
    max_speed = std::max(max_speed, speed);
    max_rate = std::max(max_rate, turn_rate);
    path += step.translation().norm();
    hover_frames = speed < 0.02 && turn_rate < 2 ? hover_frames + 1 : 0;
    longest_hover = std::max(longest_hover, hover_frames);
    fast_frames += speed > 1.8;
    spin_frames += turn_rate > 80;
  }
  EXPECT_GT(path, 400.0);  // ~0.8 m/s on average over ten minutes
  EXPECT_GT(max_speed, 1.9);
  EXPECT_LE(max_speed, 2.05);
  EXPECT_GT(max_rate, 85.0);
  EXPECT_LE(max_rate, 100.0);  // the spin's 90 deg/s and a little roll
  EXPECT_GT(fast_frames, 10 * rate);  // seconds at ~2 m/s
  EXPECT_GT(spin_frames, 10 * rate);  // seconds of spinning
  EXPECT_GE(longest_hover, 1.0 * rate);
  EXPECT_GT(z_max - z_min, 1.0);  // height changes
  EXPECT_GE(returns_to_start, 4);  // back in the first room after each tour
  // A short flight is the start of the long one.
  const SyntheticScene short_flight(parsed("flight,minutes=2"));
  EXPECT_LT((short_flight.groundTruthPose(3000).inverse() * flight.groundTruthPose(3000)).log().norm(),
            1e-12);
}

TEST(SyntheticScene, FlightSeesGlassPlainWallsAndSurfacesBeyondTheDepthRange) {
  const SyntheticScene flight(parsed("flight,minutes=2"));
  int glass = 0, far = 0, plain = 0;
  for (size_t i = 0; i < flight.numFrames(); i += 30) {
    cv::Mat surfaces;
    const RgbdFrame frame = flight.renderPose(flight.groundTruthPose(i), i, &surfaces);
    const double pixels = static_cast<double>(surfaces.total());
    glass += cv::countNonZero(surfaces == static_cast<int>(SyntheticSurface::kGlass)) > 0.2 * pixels;
    // No depth on diffuse surfaces: beyond the range (4.5 m).
    const cv::Mat no_depth = (frame.depth == 0) & (surfaces == static_cast<int>(SyntheticSurface::kDiffuse));
    far += cv::countNonZero(no_depth) > 0.5 * pixels;
    cv::Mat grey, gx, gy;
    cv::cvtColor(frame.colour, grey, cv::COLOR_BGR2GRAY);
    cv::Sobel(grey, gx, CV_32F, 1, 0);
    cv::Sobel(grey, gy, CV_32F, 0, 1);
    cv::Mat magnitude = cv::abs(gx) + cv::abs(gy);
    plain += cv::countNonZero(magnitude < 40) > 0.7 * pixels;  // image noise alone: ~20
  }
  EXPECT_GE(glass, 3) << "frames (of 120) mostly seeing glass";
  EXPECT_GE(far, 3) << "frames (of 120) mostly beyond the depth range";
  EXPECT_GE(plain, 3) << "frames (of 120) mostly seeing plain surfaces";
}

// The lookalike rooms: every pose of the first room's full turn, moved 14 m east into the
// second, sees the same image pixel for pixel, except through the doors (a closet behind
// the first room's west door, the corridor behind the second's). The flight passes both.
TEST(SyntheticScene, TwinsAreAlikePixelForPixelAwayFromTheirDoors) {
  const SyntheticScene twins(parsed("twins"));
  const Vec3 shift(14.0, 0.0, 0.0);
  int identical = 0, views = 0;
  double min_equal_share = 1.0;
  for (size_t i = 350; i <= 470; i += 10) {  // the turn in the first room
    const SE3 T_a = twins.groundTruthPose(i);
    ASSERT_LT((T_a.translation() - Vec3(4.0, 3.5, 1.4)).norm(), 0.02) << "frame " << i << " is not on A's spot";
    const RgbdFrame a = twins.renderPose(T_a, i);
    const RgbdFrame b = twins.renderPose(SE3(T_a.rotation(), T_a.translation() + shift), i);
    const cv::Mat equal = (a.depth == b.depth);
    const double share = cv::countNonZero(equal) / static_cast<double>(equal.total());
    min_equal_share = std::min(min_equal_share, share);
    identical += share == 1.0 && cv::norm(a.colour, b.colour, cv::NORM_INF) == 0;
    ++views;
  }
  EXPECT_GE(identical, views / 2) << "of " << views << " views, identical in both rooms";
  EXPECT_GT(min_equal_share, 0.5) << "share of the depth image alike, at least";
  bool in_b = false, back_in_a = false;
  for (size_t i = 0; i < twins.numFrames(); i += 30) {
    const Vec3 p = twins.groundTruthPose(i).translation();
    in_b = in_b || (p.x() > 15.0 && p.x() < 21.0);
    back_in_a = back_in_a || (in_b && p.x() < 7.0);
  }
  EXPECT_TRUE(in_b && back_in_a) << "the flight does not go into the second room and back";
}

// ---- rendering

TEST(SyntheticScene, FrameFieldsAreFilledIn) {
  const SyntheticScene scene(parsed("room,frames=5"));
  const RgbdFrame frame = scene.render(3);
  EXPECT_EQ(frame.colour.type(), CV_8UC3);
  EXPECT_EQ(frame.depth.type(), CV_16UC1);
  EXPECT_EQ(frame.width(), 640);
  EXPECT_EQ(frame.height(), 480);
  EXPECT_EQ(frame.depth.size(), frame.colour.size());
  EXPECT_EQ(frame.seq, 3);
  EXPECT_EQ(frame.utime, scene.frameUtime(3));
  EXPECT_DOUBLE_EQ(frame.depth_scale, 5000.0);
  EXPECT_EQ(frame.camera_name, "synthetic");
}

TEST(SyntheticScene, SameOptionsGiveIdenticalFrames) {
  for (const std::string spec : {"room,seed=5", "corridor,seed=5,depth_fraction=0.5"}) {
    const SyntheticScene a(parsed(spec)), b(parsed(spec));
    for (const size_t i : {0, 17, 150}) {
      const RgbdFrame fa = a.render(i), fb = b.render(i), fa2 = a.render(i);
      EXPECT_TRUE(identical(fa.colour, fb.colour)) << spec << " frame " << i;
      EXPECT_TRUE(identical(fa.depth, fb.depth)) << spec << " frame " << i;
      EXPECT_TRUE(identical(fa.colour, fa2.colour)) << spec << " frame " << i;
      EXPECT_TRUE(identical(fa.depth, fa2.depth)) << spec << " frame " << i;
    }
  }
  // Another seed gives another scene, and consecutive frames differ (noise and motion).
  const SyntheticScene one(parsed("room,seed=1")), two(parsed("room,seed=2"));
  EXPECT_FALSE(identical(one.render(0).colour, two.render(0).colour));
  EXPECT_FALSE(identical(one.render(0).colour, one.render(1).colour));
}

// Of a grid of pixels with depth in frames 100 and 400, how many unproject (with 'camera')
// to the point that a view from frames 112 / 385, turned to put the point on a pixel
// centre, sees at that pixel within 'tolerance_m'. Sets *checked to the pixels tried.
int agreeingPoints(const SyntheticScene& scene, const PinholeCamera& camera, double tolerance_m,
                   int* checked) {
  int matched = 0;
  *checked = 0;
  for (const auto& [i, j] : {std::pair<size_t, size_t>{100, 112}, {400, 385}}) {
    const RgbdFrame frame_i = scene.render(i);
    const SE3 T_w_ci = scene.groundTruthPose(i), T_w_cj = scene.groundTruthPose(j);
    for (int v = 30; v < camera.height - 30; v += 70) {
      for (int u = 30; u < camera.width - 30; u += 90) {
        const double z = depthAt(frame_i, u, v);
        if (z <= 0) continue;
        const Vec3 p_w = T_w_ci * camera.unproject(Eigen::Vector2d(u, v), z);
        // Turn camera j slightly so that p_w falls exactly on the nearest pixel centre.
        const Vec3 p_cj = T_w_cj.inverse() * p_w;
        const auto uv = camera.project(p_cj);
        if (!uv || !camera.inImage(*uv, 2)) continue;
        const Eigen::Vector2d pixel(std::round(uv->x()), std::round(uv->y()));
        const Vec3 bearing = camera.unproject(pixel, 1.0).normalized();
        const Vec3 axis = bearing.cross(p_cj.normalized());
        const double angle = std::atan2(axis.norm(), bearing.dot(p_cj.normalized()));
        const Mat3 R_cj_c = axis.norm() > 1e-12 ? expSO3(axis.normalized() * angle)
                                                : Mat3::Identity().eval();
        const SE3 T_w_c = T_w_cj * SE3(R_cj_c, Vec3::Zero());
        const RgbdFrame frame_j = scene.renderPose(T_w_c, j);
        const double z_j = depthAt(frame_j, static_cast<int>(pixel.x()), static_cast<int>(pixel.y()));
        const Vec3 p_w_again = T_w_c * camera.unproject(pixel, z_j);
        ++*checked;
        matched += z_j > 0 && (p_w_again - p_w).norm() < tolerance_m;
      }
    }
  }
  return matched;
}

TEST(SyntheticScene, UnprojectedDepthLiesOnTheSurfaceSeenFromElsewhere) {
  const SyntheticScene scene(noiseFree(parsed("room")));
  int checked = 0;
  const int matched = agreeingPoints(scene, scene.camera(), 1e-3, &checked);
  ASSERT_GE(checked, 30);
  // A few points may be hidden from the other view; all others agree to 1 mm.
  EXPECT_GE(matched, checked * 9 / 10) << matched << " of " << checked;
}

// Rendered through the TUM fr1 Kinect's lens distortion, depth and pixels agree through the
// distorted camera model (to 1 cm: depth comes from the nearest pixel of the ideal canvas,
// up to half a pixel away). (That ignoring the model costs accuracy is shown end to end by
// tests/integration/test_rgbd_slam_distortion.sh.)
TEST(SyntheticScene, DistortedFramesFollowTheDistortedCameraModel) {
  const SyntheticScene scene(
      noiseFree(parsed("room,distortion=0.2624:-0.9531:-0.0054:0.0026:1.1633")));
  ASSERT_TRUE(scene.camera().hasDistortion());
  EXPECT_DOUBLE_EQ(scene.camera().k3, 1.1633);
  int checked = 0;
  const int matched = agreeingPoints(scene, scene.camera(), 0.01, &checked);
  ASSERT_GE(checked, 30);
  EXPECT_GE(matched, checked * 9 / 10) << matched << " of " << checked;
  // The same view without distortion differs where the lens bends rays (the image border).
  const RgbdFrame plain = SyntheticScene(noiseFree(parsed("room"))).render(100);
  const RgbdFrame bent = scene.render(100);
  EXPECT_FALSE(identical(plain.colour(cv::Rect(0, 0, 40, 40)), bent.colour(cv::Rect(0, 0, 40, 40))));
}

TEST(SyntheticScene, DepthNoiseFollowsTheKinectModel) {
  SyntheticOptions noisy = parsed("room,quantise=0");
  const SyntheticScene truth(noiseFree(noisy)), measured(noisy);
  const double a = noisy.noise.sigma_coefficient;
  double sum = 0, sum_sq = 0;
  int count = 0;
  for (const size_t i : {0, 60, 120, 180, 240, 300, 360, 420, 480, 540}) {
    const cv::Mat exact = truth.render(i).depthMetres(), noisy_depth = measured.render(i).depthMetres();
    for (int v = 0; v < exact.rows; ++v) {
      for (int u = 0; u < exact.cols; ++u) {
        const float z = exact.at<float>(v, u), z_n = noisy_depth.at<float>(v, u);
        if (!(z >= 1.8f && z <= 2.2f) || std::isnan(z_n)) continue;
        const double r = (z_n - z) / (a * z * z);
        sum += r, sum_sq += r * r, ++count;
      }
    }
  }
  ASSERT_GT(count, 10000);
  const double mean = sum / count, std = std::sqrt(sum_sq / count - mean * mean);
  EXPECT_NEAR(std, 1.0, 0.2) << "normalised depth error std over " << count << " pixels";
  EXPECT_NEAR(mean, 0.0, 0.05);
}

TEST(SyntheticScene, QuantisedDepthLiesOnTheDisparityGrid) {
  SyntheticOptions options = parsed("room,noise_sigma=0");
  const SyntheticScene scene(options);
  const KinectNoiseOptions& n = options.noise;
  const double fbs = n.disparity_focal_px * n.baseline_m / n.disparity_step_px;
  const cv::Mat depth = scene.render(50).depthMetres();
  int count = 0, off_grid = 0;
  for (int v = 0; v < depth.rows; v += 3) {
    for (int u = 0; u < depth.cols; u += 3) {
      const float z = depth.at<float>(v, u);
      if (std::isnan(z)) continue;
      const double steps = fbs / z;
      ++count;
      off_grid += std::abs(steps - std::round(steps)) > 0.05;
    }
  }
  ASSERT_GT(count, 10000);
  EXPECT_EQ(off_grid, 0);
}

TEST(SyntheticScene, NoReadingOutsideTheRangeLimits) {
  // Exact depth with a wide range shows there is something to cut; the default cuts it.
  SyntheticOptions wide = noiseFree(parsed("corridor,frames=300"));
  wide.noise.min_range_m = 0.05, wide.noise.max_range_m = 13.0;
  const SyntheticScene exact(wide), kinect(parsed("corridor,frames=300"));
  // Frame 10, and frame 10 moved to 0.3 m in front of whatever is at the image centre.
  const SE3 T = exact.groundTruthPose(10);
  const double centre_z = depthAt(exact.render(10), 320, 240);
  ASSERT_GT(centre_z, 0.5);
  const SE3 T_close(T.rotation(), T.translation() + T.rotationMatrix() * Vec3(0, 0, centre_z - 0.3));
  for (const SE3& pose : {T, T_close}) {
    const cv::Mat wide_depth = exact.renderPose(pose, 10).depthMetres();
    const cv::Mat depth = kinect.renderPose(pose, 10).depthMetres();
    double wide_min, wide_max, min, max;
    cv::minMaxIdx(wide_depth, &wide_min, &wide_max, nullptr, nullptr, wide_depth == wide_depth);
    cv::minMaxIdx(depth, &min, &max, nullptr, nullptr, depth == depth);
    EXPECT_TRUE(wide_min < 0.5 || wide_max > 4.5) << wide_min << " " << wide_max;
    EXPECT_GE(min, 0.5);
    EXPECT_LE(max, 4.5);
  }
}

TEST(SyntheticScene, RoomPixelsMostlyHaveDepth) {
  const SyntheticScene scene(parsed("room"));
  double valid = 0;
  int frames = 0;
  for (size_t i = 0; i < scene.numFrames(); i += 50, ++frames) {
    valid += cv::countNonZero(scene.render(i).depth) / (640.0 * 480.0);
  }
  EXPECT_GT(valid / frames, 0.8);
}

TEST(SyntheticScene, DepthFractionKeepsThatShareOfTheReadings) {
  const SyntheticScene dense(parsed("room")), sparse(parsed("room,depth_fraction=0.3"));
  for (const size_t i : {0, 200}) {
    const cv::Mat all = dense.render(i).depth, kept = sparse.render(i).depth;
    const int n_all = cv::countNonZero(all), n_kept = cv::countNonZero(kept);
    ASSERT_GT(n_all, 100000);
    EXPECT_NEAR(static_cast<double>(n_kept) / n_all, 0.3, 0.01);
    // The kept readings are exactly the dense ones.
    cv::Mat dense_at_kept;
    all.copyTo(dense_at_kept, kept != 0);
    EXPECT_TRUE(identical(dense_at_kept, kept));
  }
}

TEST(SyntheticScene, DepthCanBeSwitchedOffOrLimitedToTheFirstFrames) {
  const SyntheticScene off(parsed("room,depth=off,frames=3"));
  for (size_t i = 0; i < 3; ++i) EXPECT_EQ(cv::countNonZero(off.render(i).depth), 0);
  EXPECT_GT(cv::countNonZero(off.render(0).grey()), 0);  // colour is still there
  const SyntheticScene first(parsed("room,depth=first,frames=3"));
  EXPECT_GT(cv::countNonZero(first.render(0).depth), 100000);
  EXPECT_EQ(cv::countNonZero(first.render(1).depth), 0);
  const SyntheticScene some(parsed("room,depth_frames=2,frames=3"));
  EXPECT_GT(cv::countNonZero(some.render(1).depth), 100000);
  EXPECT_EQ(cv::countNonZero(some.render(2).depth), 0);
}

TEST(SyntheticScene, CorridorGlassAndBlackSurfacesGiveHolesButColour) {
  const SyntheticScene scene(parsed("corridor"));
  int glass_total = 0, black_total = 0, frames_with_glass = 0;
  for (size_t i = 0; i < scene.numFrames(); i += 150) {
    cv::Mat surfaces;
    const RgbdFrame frame = scene.renderPose(scene.groundTruthPose(i), i, &surfaces);
    const cv::Mat glass = surfaces == static_cast<int>(SyntheticSurface::kGlass);
    const cv::Mat black = surfaces == static_cast<int>(SyntheticSurface::kBlack);
    const cv::Mat diffuse = surfaces == static_cast<int>(SyntheticSurface::kDiffuse);
    EXPECT_EQ(cv::countNonZero(surfaces == static_cast<int>(SyntheticSurface::kNothing)), 0);
    const cv::Mat with_depth = frame.depth != 0;
    EXPECT_EQ(cv::countNonZero(glass & with_depth), 0) << "frame " << i;
    EXPECT_EQ(cv::countNonZero(black & with_depth), 0) << "frame " << i;
    EXPECT_GT(cv::countNonZero(diffuse & with_depth), 50000) << "frame " << i;
    const int n_glass = cv::countNonZero(glass);
    glass_total += n_glass, black_total += cv::countNonZero(black);
    if (n_glass > 2000) {
      ++frames_with_glass;
      cv::Scalar mean, stddev;
      cv::meanStdDev(frame.grey(), mean, stddev, glass);
      EXPECT_GT(mean[0], 20.0) << "glass has colour, frame " << i;
      EXPECT_GT(stddev[0], 5.0) << "glass has texture, frame " << i;
    }
  }
  EXPECT_GE(frames_with_glass, 5);
  EXPECT_GT(black_total, 10000);
  EXPECT_GT(glass_total, 100000);
}

TEST(SyntheticScene, RoomTextureHasFastCornersAtSeveralScales) {
  const SyntheticScene scene(parsed("room"));
  for (const size_t i : {0, 150, 300, 450}) {
    cv::Mat level = scene.render(i).grey();
    const int minimum[3] = {300, 150, 50};
    for (int l = 0; l < 3; ++l) {
      const int corners = countFastCorners(level, 20);
      EXPECT_GT(corners, minimum[l]) << "frame " << i << " level " << l;
      cv::Mat half;
      cv::pyrDown(level, half);
      level = half;
    }
  }
}

// ---- output

TEST(SyntheticScene, TumDirectoryReadsBackExactly) {
  test::TempDir dir;
  const SyntheticScene scene(parsed("room,frames=3,seed=4"));
  const Status written = scene.writeTumDirectory(dir.path());
  ASSERT_TRUE(written.ok()) << written.error();
  for (const std::string list : {"rgb.txt", "depth.txt"}) {
    std::ifstream file(dir.file(list));
    ASSERT_TRUE(file) << list;
    std::string line;
    size_t i = 0;
    while (std::getline(file, line)) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream in(line);
      double t;
      std::string name;
      ASSERT_TRUE(in >> t >> name) << line;
      ASSERT_LT(i, 3u);
      EXPECT_NEAR(t, scene.frameUtime(i) * 1e-6, 1e-6);
      const RgbdFrame frame = scene.render(i);
      const cv::Mat image = cv::imread(dir.file(name), cv::IMREAD_UNCHANGED);
      EXPECT_TRUE(identical(image, list == "rgb.txt" ? frame.colour : frame.depth)) << name;
      ++i;
    }
    EXPECT_EQ(i, 3u) << list;
  }
  const auto truth = readTumTrajectory(dir.file("groundtruth.txt"));
  ASSERT_TRUE(truth.ok()) << truth.error();
  ASSERT_EQ(truth->size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_NEAR((*truth)[i].t, scene.frameUtime(i) * 1e-6, 1e-6);
    EXPECT_LT((scene.groundTruthPose(i).inverse() * (*truth)[i].T_w_c).log().norm(), 1e-7);
  }
}

TEST(SyntheticScene, FrameSourceRendersEveryFrameThenEnds) {
  const SyntheticOptions options = parsed("room,frames=3,seed=9");
  const auto source = makeSyntheticSource(options);
  ASSERT_TRUE(source);
  EXPECT_EQ(source->size(), std::optional<size_t>(3));
  EXPECT_DOUBLE_EQ(source->nominalRateHz(), 30.0);
  EXPECT_NE(source->describe().find("seed=9"), std::string::npos) << source->describe();
  const SyntheticScene scene(options);
  for (size_t i = 0; i < 3; ++i) {
    const FrameResult result = source->next();
    ASSERT_EQ(result.status, FrameResult::Status::kFrame);
    EXPECT_EQ(result.frame.seq, static_cast<int64_t>(i));
    EXPECT_TRUE(identical(result.frame.depth, scene.render(i).depth));
  }
  EXPECT_EQ(source->next().status, FrameResult::Status::kEnd);
}

// A 1 s gap (issue 3): the dropped frames are left out, the others keep their index and
// timestamp, and the scene and its ground truth are those of the same scene without drops.
TEST(SyntheticScene, DroppedFramesLeaveAGapAndKeepTimestamps) {
  const SyntheticOptions options = parsed("room,frames=10,drop=3-5");
  const auto source = makeSyntheticSource(options);
  EXPECT_EQ(source->size(), std::optional<size_t>(7));
  const SyntheticScene plain(parsed("room,frames=10"));
  std::vector<int64_t> seqs;
  for (int i = 0; i < 20; ++i) {  // bounded: 7 frames then the end
    const FrameResult result = source->next();
    if (result.status == FrameResult::Status::kEnd) break;
    ASSERT_EQ(result.status, FrameResult::Status::kFrame);
    const size_t seq = static_cast<size_t>(result.frame.seq);
    seqs.push_back(result.frame.seq);
    EXPECT_EQ(result.frame.utime, plain.frameUtime(seq));
    EXPECT_TRUE(identical(result.frame.colour, plain.render(seq).colour)) << "frame " << seq;
  }
  EXPECT_EQ(seqs, (std::vector<int64_t>{0, 1, 2, 6, 7, 8, 9}));
  const SyntheticScene dropped(options);
  EXPECT_EQ(dropped.numFrames(), 10u);
  EXPECT_EQ(dropped.groundTruth().size(), 10u);
  EXPECT_LT((dropped.groundTruthPose(4).inverse() * plain.groundTruthPose(4)).log().norm(), 1e-12);
  // A range past the end drops what it covers; one index drops one frame.
  EXPECT_EQ(makeSyntheticSource(parsed("room,frames=10,drop=8-20"))->size(),
            std::optional<size_t>(8));
  EXPECT_EQ(makeSyntheticSource(parsed("room,frames=10,drop=0"))->next().frame.seq, 1);
}

// Every other frame (issue 3's fast motion): frames 0, 2, 4, ... with their own timestamps.
TEST(SyntheticScene, EveryKeepsEveryKthFrame) {
  const auto source = makeSyntheticSource(parsed("room,frames=9,every=2"));
  EXPECT_EQ(source->size(), std::optional<size_t>(5));
  const SyntheticScene plain(parsed("room,frames=9"));
  std::vector<int64_t> seqs;
  for (int i = 0; i < 20; ++i) {  // bounded: 5 frames then the end
    const FrameResult result = source->next();
    if (result.status == FrameResult::Status::kEnd) break;
    ASSERT_EQ(result.status, FrameResult::Status::kFrame);
    seqs.push_back(result.frame.seq);
    EXPECT_EQ(result.frame.utime, plain.frameUtime(static_cast<size_t>(result.frame.seq)));
  }
  EXPECT_EQ(seqs, (std::vector<int64_t>{0, 2, 4, 6, 8}));
  // With a gap as well: both leave frames out.
  EXPECT_EQ(makeSyntheticSource(parsed("room,frames=9,every=2,drop=2-4"))->size(),
            std::optional<size_t>(3));
}

// Other cameras: the size and intrinsics reach the camera and the rendered frames.
TEST(SyntheticScene, SizeAndIntrinsicsMakeAnotherCamera) {
  const SyntheticScene scene(parsed("room,frames=2,size=320x240,intrinsics=300:290:150:125"));
  const PinholeCamera& camera = scene.camera();
  EXPECT_EQ(camera.width, 320);
  EXPECT_EQ(camera.height, 240);
  EXPECT_DOUBLE_EQ(camera.fx, 300.0);
  EXPECT_DOUBLE_EQ(camera.fy, 290.0);
  EXPECT_DOUBLE_EQ(camera.cx, 150.0);
  EXPECT_DOUBLE_EQ(camera.cy, 125.0);
  const RgbdFrame frame = scene.render(1);
  EXPECT_EQ(frame.colour.size(), cv::Size(320, 240));
  EXPECT_EQ(frame.depth.size(), cv::Size(320, 240));
  EXPECT_GT(cv::countNonZero(frame.depth), 320 * 240 / 2);
}

// A covered camera (issue 3): the covered frames are delivered, dark, textureless and
// without depth; the frames around are those of the plain scene.
TEST(SyntheticScene, CoveredFramesAreDarkWithoutDepth) {
  const SyntheticScene covered(parsed("room,frames=6,cover=2-3"));
  const SyntheticScene plain(parsed("room,frames=6"));
  EXPECT_EQ(makeSyntheticSource(covered.options())->size(), std::optional<size_t>(6));
  for (size_t i = 0; i < 6; ++i) {
    const RgbdFrame frame = covered.render(i);
    if (i == 2 || i == 3) {
      EXPECT_EQ(cv::countNonZero(frame.depth), 0) << "frame " << i;
      cv::Scalar mean, stddev;
      cv::meanStdDev(frame.colour, mean, stddev);
      EXPECT_LT(mean[0], 12.0) << "frame " << i;
      EXPECT_LT(stddev[0], 4.0) << "frame " << i;  // image noise only (sigma 2)
    } else {
      EXPECT_TRUE(identical(frame.colour, plain.render(i).colour)) << "frame " << i;
      EXPECT_TRUE(identical(frame.depth, plain.render(i).depth)) << "frame " << i;
    }
  }
}

// trueDepth is the depth a noise-free sensor reads where it reads any, and has a depth
// where the sensor reads none: glass and the corridor's far end beyond the 4.5 m range.
TEST(SyntheticScene, TrueDepthIsTheSensorsDepthWithoutItsHoles) {
  const SyntheticScene scene(*parseSyntheticSpec("corridor,frames=10,noise_sigma=0,depth_sigma=0,quantise=0"));
  const cv::Mat measured = scene.render(0).depthMetres();
  const cv::Mat truth = scene.trueDepth(scene.groundTruthPose(0));
  ASSERT_EQ(truth.type(), CV_32FC1);
  ASSERT_EQ(truth.size(), measured.size());
  int compared = 0, only_true = 0, far = 0;
  double worst = 0.0;
  for (int v = 0; v < truth.rows; ++v) {
    for (int u = 0; u < truth.cols; ++u) {
      const float t = truth.at<float>(v, u), m = measured.at<float>(v, u);
      ASSERT_TRUE(std::isfinite(t)) << "the corridor is closed: every ray hits something";
      if (std::isfinite(m)) {
        ++compared;
        worst = std::max(worst, static_cast<double>(std::abs(t - m)));
      } else {
        ++only_true;
        far += t > 4.5f;
      }
    }
  }
  EXPECT_GT(compared, truth.total() / 4);
  EXPECT_LT(worst, 1e-3) << "without noise and quantisation the sensor reads the truth";
  EXPECT_GT(only_true, 1000) << "the far end and glass give no reading, but have a depth";
  EXPECT_GT(far, 1000);
}

}  // namespace
}  // namespace rgbdslam
