// LoopCloser: a return to a place mapped long before takes the drift out of every keyframe
// and moves the points with their keyframes; a lookalike place far away closes nothing; a
// part of the map started where the tracker was lost joins the rest where it sees a place of
// it, within the reach of the vehicle's speed, and not at a lookalike place beyond it.
#include "rgbdslam/mapping/loop_closer.h"

#include <gtest/gtest.h>

#include <algorithm>
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
  // Each recognised place is recorded with its edge as measured and both keyframes' times
  // (rgbd-slam audits them against the truth: eval/loop_audit.h). The closing edge agrees
  // with the room's truth, whatever the drift the map had.
  const auto& places = closer.recognised();
  const auto closed = std::find_if(places.begin(), places.end(), [](const LoopClosureResult& r) { return r.closed; });
  ASSERT_NE(closed, places.end()) << places.size() << " places recorded, none closed";
  const LoopClosureResult& recorded = *closed;
  EXPECT_EQ(recorded.with, closing.with);
  EXPECT_EQ(recorded.with_utime, map.keyframe(closing.with)->utime);
  int query = -1;
  for (int k = 0; k < keyframes; ++k) {
    if (map.keyframe(k)->utime == recorded.query_utime) query = k;
  }
  ASSERT_GE(query, 0) << "no keyframe at the recorded query time " << recorded.query_utime;
  const SE3 edge_error = (truth[closing.with].inverse() * truth[query]).inverse() * recorded.T_with_query;
  EXPECT_LT(edge_error.translation().norm(), 0.03);
  EXPECT_LT(edge_error.log().tail<3>().norm() * 180.0 / M_PI, 1.0);
  EXPECT_FALSE(changes.keyframes.empty());
  for (int k = 0; k < keyframes; ++k) {  // every point still 2 m in front of its keyframe
    const Keyframe& kf = *map.keyframe(k);
    EXPECT_LT((kf.T_c_w() * map.point(k)->p_w - Vec3(0.0, 0.0, 2.0)).norm(), 1e-9) << "point of keyframe " << k;
  }
}

// The drifting room of the test above, on to frame 1180. After a closure the tracker has the
// corrected map: the keyframes after it come in the corrected frame and see the old place
// again. Returns the loop closer's counters.
LoopClosureCounters revisitAfterAClosure(double agree_sigmas) {
  const int keyframes = kLoopLastFrame / kLoopFrameStep + 1;  // drift as in the test above...
  const int more = 9;                                         // ...then on to frame 1180
  Map map;
  LoopClosureOptions options;
  options.agree_sigmas = agree_sigmas;
  LoopCloser closer(loopRoom().camera(), options);
  MapChanges changes;
  SE3 correction;  // what the last closure did to the newest keyframe: applied to the ones after
  for (int k = 0; k < keyframes + more; ++k) {
    const int frame = k * kLoopFrameStep;
    const SE3 drifted = loopDrifted(loopRoom().groundTruthPose(static_cast<size_t>(frame)), static_cast<double>(k) / (keyframes - 1));
    map.addKeyframe(loopKeyframe(k, frame, correction * drifted));
    const size_t changed_before = changes.keyframes.size();
    const LoopClosureResult result = closer.onKeyframe(&map, k, &changes);
    if (!describe(result).empty()) std::printf("agree_sigmas %.0f, keyframe %d: %s\n", agree_sigmas, k, describe(result).c_str());
    if (result.closed) {
      EXPECT_GT(result.disagreement_sigmas, agree_sigmas);
      correction = map.keyframe(k)->T_w_c * drifted.inverse();
    }
    if (result.agreed) {
      EXPECT_LE(result.disagreement_sigmas, agree_sigmas);
      EXPECT_EQ(result.graph_ms, 0.0) << "keyframe " << k << ": a graph was solved for a loop the map agrees with";
      EXPECT_EQ(changes.keyframes.size(), changed_before) << "keyframe " << k << " moved the map";
    }
  }
  return closer.counters();
}

// Without the gate every recognition of the revisit solved the graph and moved the whole map
// by the loop measurement's noise (5-25 mm here, past min_correction_*).
TEST(LoopCloser, ClosesOnceAndThenAgrees) {
  const LoopClosureCounters gated = revisitAfterAClosure(LoopClosureOptions{}.agree_sigmas);
  const LoopClosureCounters ungated = revisitAfterAClosure(0.0);
  EXPECT_GE(gated.closed, 1);
  EXPECT_GE(gated.agreed, 5) << "the keyframes after the closure should find the map agreeing";
  EXPECT_EQ(ungated.agreed, 0);
  EXPECT_LT(2 * gated.closed, ungated.closed);
  std::printf("places recognised %ld / %ld, closed %ld / %ld, agreed %ld / %ld (agree_sigmas %.1f / 0)\n", gated.recognised,
              ungated.recognised, gated.closed, ungated.closed, gated.agreed, ungated.agreed,
              LoopClosureOptions{}.agree_sigmas);
}

// A session that extends a saved map (rgbd-slam / rgbd-mapper --load-map): the loaded
// keyframes, frames 0-400 at their saved poses, enter the loop closer as Mapper::load
// enters them (places only, close=false); the session's keyframes, frames 420-1000, drift to
// 12 cm and 3 deg, and the last ones see again the loaded place: the loop closes into the
// loaded map, whose keyframes stay where the file put them (all held fixed in the graph).
TEST(LoopCloser, ClosesALoopIntoALoadedMap) {
  constexpr int kLoadedLast = 20;  // keyframes 0-20: frames 0-400, from the file
  const int keyframes = kLoopLastFrame / kLoopFrameStep + 1;
  Map map;
  LoopCloser closer(loopRoom().camera(), LoopClosureOptions{});
  MapChanges changes;
  std::vector<SE3> truth;
  std::vector<LoopClosureResult> closures;
  double drift_before = 0.0;
  for (int k = 0; k < keyframes; ++k) {
    const int frame = k * kLoopFrameStep;
    truth.push_back(loopRoom().groundTruthPose(static_cast<size_t>(frame)));
    const bool loaded = k <= kLoadedLast;
    const double drift = loaded ? 0.0 : static_cast<double>(k - kLoadedLast) / (keyframes - 1 - kLoadedLast);
    const Keyframe* kf = map.addKeyframe(loopKeyframe(k, frame, loopDrifted(truth.back(), drift)));
    drift_before = std::max(drift_before, loopErrorM(kf->T_w_c, truth.back()));
    const LoopClosureResult result = closer.onKeyframe(&map, k, &changes, /*close=*/!loaded);
    if (loaded) {
      EXPECT_FALSE(result.tried) << "loaded keyframe " << k << " queried";
    }
    if (result.closed) closures.push_back(result);
  }
  ASSERT_FALSE(closures.empty()) << closer.counters().queries << " queries, " << closer.counters().recognised << " recognised";
  EXPECT_LE(closures.front().with, kLoadedLast) << "closed with a keyframe of the session, not of the loaded map";
  for (int k = 0; k <= kLoadedLast; ++k) {
    EXPECT_LT(loopErrorM(map.keyframe(k)->T_w_c, truth[k]), 0.01) << "loaded keyframe " << k << " moved off its pose";
  }
  double drift_after = 0.0;
  for (int k = keyframes - 3; k < keyframes; ++k) drift_after = std::max(drift_after, loopErrorM(map.keyframe(k)->T_w_c, truth[k]));
  EXPECT_LT(drift_after, drift_before / 3) << "drift " << drift_before << " m before the closure";
  std::printf("closed into the loaded map with keyframe %ld: correction %.3f m %.2f deg; the session's end %.3f m off "
              "(%.3f m before)\n", static_cast<long>(closures.front().with), closures.front().correction_m,
              closures.front().correction_deg, drift_after, drift_before);
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

// The room mapped over frames 0-440 (part 0), then, after a loss, a new part over frames
// 800-1000 (which see again the place of frames ~0-450) whose poses are the truth moved by
// what the tracker coasted wrong: 1.5 m and 20 deg. Returns the keyframes' true poses.
std::vector<SE3> mapWithASecondPart(Map* map, LoopCloser* closer, MapChanges* changes,
                                    std::vector<LoopClosureResult>* results) {
  const SE3 coasted_wrong(Mat3(Eigen::AngleAxisd(20.0 * M_PI / 180.0, Vec3::UnitY()).toRotationMatrix()),
                          Vec3(1.5, 0.0, -0.5));
  std::vector<SE3> truth;
  KeyframeId id = 0;
  for (const bool second : {false, true}) {
    const KeyframeId part = id;
    for (int frame = second ? 800 : 0; frame <= (second ? 1000 : 440); frame += kLoopFrameStep) {
      truth.push_back(loopRoom().groundTruthPose(static_cast<size_t>(frame)));
      Keyframe* kf = map->addKeyframe(loopKeyframe(id, frame, second ? coasted_wrong * truth.back() : truth.back()));
      kf->part = part;
      MapPoint point;  // one point per keyframe, 2 m in front of it
      point.id = id;
      point.source_keyframe = id;
      point.p_w = kf->T_w_c * Vec3(0.0, 0.0, 2.0);
      map->addPoint(point);
      results->push_back(closer->onKeyframe(map, id, changes));
      ++id;
    }
  }
  return truth;
}

TEST(LoopCloser, JoinsANewPartWhereItSeesAPlaceOfTheOld) {
  Map map;
  LoopCloser closer(loopRoom().camera(), LoopClosureOptions{});
  MapChanges changes;
  std::vector<LoopClosureResult> results;
  const std::vector<SE3> truth = mapWithASecondPart(&map, &closer, &changes, &results);
  const KeyframeId second_part = 23;  // frame 800's keyframe
  const auto joined = std::find_if(results.begin(), results.end(), [](const LoopClosureResult& r) { return r.joined_part >= 0; });
  ASSERT_NE(joined, results.end()) << closer.counters().queries << " queries, " << closer.counters().recognised << " recognised";
  EXPECT_EQ(joined->joined_part, second_part);
  EXPECT_EQ(joined->joined_to, 0);
  EXPECT_TRUE(joined->closed);
  EXPECT_GT(joined->correction_m, 1.0);
  EXPECT_EQ(closer.counters().parts_joined, 1);
  double worst_m = 0.0;
  for (const auto& [id, kf] : map.keyframes()) {
    EXPECT_EQ(kf->part, 0) << "keyframe " << id;
    if (id < second_part) EXPECT_LT(loopErrorM(kf->T_w_c, truth[id]), 1e-6) << "the old part moved: keyframe " << id;
    else worst_m = std::max(worst_m, loopErrorM(kf->T_w_c, truth[id]));
    EXPECT_LT((kf->T_c_w() * map.point(id)->p_w - Vec3(0.0, 0.0, 2.0)).norm(), 1e-9) << "point of keyframe " << id;
  }
  EXPECT_LT(worst_m, 0.05) << "the joined part's keyframes, off the truth by up to 1.6 m before";
  std::printf("part %ld joined to part 0 by keyframe %ld (with %ld): correction %.2f m %.1f deg, its keyframes %.3f m "
              "off the truth after\n", static_cast<long>(second_part), static_cast<long>(joined - results.begin()),
              static_cast<long>(joined->with), joined->correction_m, joined->correction_deg, worst_m);
}

// The same join, but the vehicle cannot have flown from the last keyframe before the loss to
// where the join puts the new part's first keyframe: refused, the parts stay apart.
TEST(LoopCloser, JoinsNoPartBeyondTheReachOfTheVehiclesSpeed) {
  Map map;
  LoopClosureOptions options;
  options.join_max_speed_m_s = 0.01;  // 12 s between the parts: 0.12 m
  options.join_margin_m = 0.0;
  LoopCloser closer(loopRoom().camera(), options);
  MapChanges changes;
  std::vector<LoopClosureResult> results;
  mapWithASecondPart(&map, &closer, &changes, &results);
  EXPECT_EQ(closer.counters().parts_joined, 0);
  EXPECT_EQ(closer.counters().closed, 0);
  EXPECT_GT(closer.counters().beyond_drift, 0);
  EXPECT_EQ(map.keyframe(30)->part, 23);
}

// Two identical rooms 10 m apart, the second entered after the first (part 0 maps the first
// room's frames 0-440, then the twin's frames 0-200). Lost there for a second, the tracker
// starts a new part over the twin's frames 240-440 (its coasted pose 0.3 m off). Its places
// look exactly like the first room's, but a join there would put the vehicle 10 m from
// where it was lost a second before: only the twin's own keyframes may take the part.
TEST(LoopCloser, JoinsNoPartToALookalikeRoomBeyondReach) {
  Map map;
  LoopCloser closer(loopRoom().camera(), LoopClosureOptions{});
  MapChanges changes;
  const SE3 twin(Mat3::Identity(), Vec3(10.0, 0.0, 0.0));
  const SE3 coasted_wrong(Mat3::Identity(), Vec3(0.3, 0.0, 0.0));
  const int64_t frame_us = loopRoom().render(1).utime - loopRoom().render(0).utime;
  struct Stretch {
    int first_frame, last_frame;
    SE3 world_from_truth;
    bool new_part;
  };
  KeyframeId id = 0, part = 0, first_twin_id = -1, new_part_id = -1;
  int64_t utime = 0;
  std::vector<SE3> truth;
  long refused_before_the_part = 0;
  for (const Stretch& stretch : {Stretch{0, 440, SE3(), false}, Stretch{0, 200, twin, false},
                                 Stretch{240, 440, coasted_wrong * twin, true}}) {
    if (stretch.new_part) part = id, new_part_id = id, refused_before_the_part = closer.counters().beyond_drift;
    if (stretch.first_frame == 0 && id > 0) first_twin_id = id;
    for (int frame = stretch.first_frame; frame <= stretch.last_frame; frame += kLoopFrameStep) {
      const SE3 T_true = loopRoom().groundTruthPose(static_cast<size_t>(frame));
      truth.push_back((stretch.new_part ? coasted_wrong.inverse() * stretch.world_from_truth : stretch.world_from_truth) * T_true);
      Keyframe* kf = map.addKeyframe(loopKeyframe(id, frame, stretch.world_from_truth * T_true));
      kf->part = part;
      kf->utime = utime;
      utime += kLoopFrameStep * frame_us;
      const LoopClosureResult result = closer.onKeyframe(&map, id, &changes);
      if (result.joined_part >= 0) {
        EXPECT_GE(result.with, first_twin_id) << "keyframe " << id << " joined its part to the first room's keyframe " << result.with;
      }
      ++id;
    }
    if (stretch.first_frame == 0 && id > 0 && !stretch.new_part) utime += 1000000 - kLoopFrameStep * frame_us;  // 1 s lost
  }
  // The new part has too few keyframes for a loop within itself: what was refused while it
  // grew was refused by the join's speed bound (the first room's places).
  EXPECT_GT(closer.counters().beyond_drift, refused_before_the_part) << "no place of the first room was refused";
  for (KeyframeId k = new_part_id; k < id; ++k) {
    EXPECT_LT(loopErrorM(map.keyframe(k)->T_w_c, truth[k]), 0.35) << "keyframe " << k;
  }
  std::printf("new part in the twin: %ld queries, %ld refused beyond reach while it grew, %ld parts joined\n",
              closer.counters().queries, closer.counters().beyond_drift - refused_before_the_part,
              closer.counters().parts_joined);
}

}  // namespace
}  // namespace rgbdslam
