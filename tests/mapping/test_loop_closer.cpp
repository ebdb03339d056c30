// LoopCloser: a return to a place mapped long before takes the drift out of every keyframe
// and moves the points with their keyframes; a lookalike place far away closes nothing.
#include "rgbdslam/mapping/loop_closer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "rgbdslam/synth/scene.h"

namespace rgbdslam {
namespace {

constexpr int kLoopFrameStep = 20;     // a keyframe every 20 frames of the room
constexpr int kLoopLastFrame = 1000;   // frame 1000 sees again the place of frames ~0-450
constexpr double kLoopDriftM = 0.12;   // odometry's position drift at the last keyframe [m]
constexpr double kLoopDriftDeg = 3.0;  // ...and its yaw drift [deg]

const SyntheticScene& loopRoom() {
  static const SyntheticScene scene(*parseSyntheticSpec("room,frames=1200"));
  return scene;
}

// The keyframe of 'frame' at 'T_w_c', built as the mapper builds one.
std::unique_ptr<Keyframe> loopKeyframe(KeyframeId id, int frame, const SE3& T_w_c) {
  const RgbdFrame rgbd = loopRoom().render(static_cast<size_t>(frame));
  KeyframeData data;
  data.utime = rgbd.utime, data.map_id = 1, data.id = id, data.T_w_c = T_w_c;
  data.grey = rgbd.grey(), data.depth = rgbd.depth, data.depth_scale = rgbd.depth_scale;
  return makeKeyframe(data, KeyframeBuildOptions{});
}

// Odometry that drifts: a growing offset and yaw about the first camera, reaching
// kLoopDriftM and kLoopDriftDeg at the last keyframe.
SE3 loopDrifted(const SE3& truth, double fraction) {
  const double yaw = fraction * kLoopDriftDeg * M_PI / 180.0;
  const SE3 drift(Mat3(Eigen::AngleAxisd(yaw, Vec3::UnitY()).toRotationMatrix()),
                  Vec3(fraction * kLoopDriftM, 0.0, 0.5 * fraction * kLoopDriftM));
  return drift * truth;
}

double loopErrorM(const SE3& a, const SE3& b) { return (a.translation() - b.translation()).norm(); }

TEST(LoopCloser, ClosesALoopAndTakesOutTheDrift) {
  const int keyframes = kLoopLastFrame / kLoopFrameStep + 1;
  Map map;
  LoopCloser closer(loopRoom().camera(), LoopClosureOptions{});
  MapChanges changes;
  LoopClosureResult closing;
  std::vector<SE3> truth;
  double drift_before = 0.0;
  for (int k = 0; k < keyframes; ++k) {
    const int frame = k * kLoopFrameStep;
    truth.push_back(loopRoom().groundTruthPose(static_cast<size_t>(frame)));
    Keyframe* kf = map.addKeyframe(loopKeyframe(k, frame, loopDrifted(truth.back(), static_cast<double>(k) / (keyframes - 1))));
    // One point per keyframe, 2 m in front of it: it must move with its keyframe.
    MapPoint point;
    point.id = k;
    point.source_keyframe = k;
    point.p_w = kf->T_w_c * Vec3(0.0, 0.0, 2.0);
    map.addPoint(point);
    drift_before = std::max(drift_before, loopErrorM(kf->T_w_c, truth.back()));
    const LoopClosureResult result = closer.onKeyframe(&map, k, &changes);
    ASSERT_FALSE(result.refused) << "keyframe " << k << " with " << result.with;
    if (result.closed && !closing.closed) closing = result;
  }
  ASSERT_TRUE(closing.closed) << closer.counters().queries << " queries, " << closer.counters().recognised << " recognised";
  EXPECT_LT(closing.with, keyframes - LoopClosureOptions{}.min_keyframe_gap);
  EXPECT_GT(closing.correction_m, 0.02);
  // After the closure the keyframes near the loop's end are within a third of the drift.
  double drift_after = 0.0;
  for (int k = keyframes - 3; k < keyframes; ++k) drift_after = std::max(drift_after, loopErrorM(map.keyframe(k)->T_w_c, truth[k]));
  EXPECT_LT(drift_after, drift_before / 3) << "drift " << drift_before << " m before, " << drift_after << " m after";
  std::printf("loop %ld -> %ld closed: drift at the end %.3f m before, %.3f m after; largest correction %.3f m %.2f deg\n",
              static_cast<long>(closing.with), static_cast<long>(keyframes - 1), drift_before, drift_after,
              closing.correction_m, closing.correction_deg);
  EXPECT_FALSE(changes.keyframes.empty());
  for (int k = 0; k < keyframes; ++k) {  // every point still 2 m in front of its keyframe
    const Keyframe& kf = *map.keyframe(k);
    EXPECT_LT((kf.T_c_w() * map.point(k)->p_w - Vec3(0.0, 0.0, 2.0)).norm(), 1e-9) << "point of keyframe " << k;
  }
}

// Two identical rooms 10 m apart: the keyframes of the second look exactly like those of
// the first, but odometry puts them 10 m away, far beyond the drift: nothing is closed.
TEST(LoopCloser, ClosesNothingInALookalikeRoom) {
  Map map;
  LoopCloser closer(loopRoom().camera(), LoopClosureOptions{});
  MapChanges changes;
  const Vec3 twin_shift(10.0, 0.0, 0.0);
  KeyframeId id = 0;
  for (const bool twin : {false, true}) {
    for (int frame = 0; frame <= 450; frame += kLoopFrameStep) {
      SE3 T_w_c = loopRoom().groundTruthPose(static_cast<size_t>(frame));
      if (twin) T_w_c = SE3(T_w_c.rotation(), T_w_c.translation() + twin_shift);
      map.addKeyframe(loopKeyframe(id, frame, T_w_c));
      const LoopClosureResult result = closer.onKeyframe(&map, id, &changes);
      EXPECT_FALSE(result.closed) << "keyframe " << id << " closed a loop with " << result.with;
      ++id;
    }
  }
  EXPECT_GT(closer.counters().queries, 0);
  EXPECT_EQ(closer.counters().closed, 0);
  EXPECT_TRUE(changes.keyframes.empty());
}

}  // namespace
}  // namespace rgbdslam
