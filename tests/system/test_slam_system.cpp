// SlamSystem: tracker and mapper in one process over the map protocol (sync/), in both run
// modes, on the synthetic room.
#include "rgbdslam/system/slam_system.h"

#include <gtest/gtest.h>

#include "rgbdslam/eval/trajectory_eval.h"
#include "rgbdslam/synth/scene.h"

namespace rgbdslam {
namespace {

constexpr size_t kFrames = 150;

const SyntheticScene& room() {
  static const SyntheticScene scene(*parseSyntheticSpec("room,frames=150"));
  return scene;
}

struct SlamRun {
  Trajectory trajectory;
  SlamStats stats;
  double ate_m = 0.0;
};

SlamRun run(bool deterministic, const LinkOptions& link = {}) {
  SlamSystem slam(room().camera(), SlamOptions{}, deterministic, link);
  SlamRun r;
  for (size_t i = 0; i < kFrames; ++i) {
    const RgbdFrame frame = room().render(i);
    const TrackResult result = slam.process(frame);
    const bool posed = result.status == TrackResult::Status::kInitialised ||
                       result.status == TrackResult::Status::kTracked ||
                       result.status == TrackResult::Status::kRelocalised;
    if (posed) r.trajectory.push_back({frame.utime * 1e-6, result.pose.T_w_c});
  }
  slam.finish();
  r.stats = slam.stats();
  const auto eval = evaluateTrajectory(room().groundTruth(), r.trajectory, EvalOptions{});
  EXPECT_TRUE(eval) << eval.error();
  if (eval) r.ate_m = eval->ate_m.rmse;
  return r;
}

// The default mode of rgbd-slam: the mapper in its own thread. finish() joins it with the
// map integrated (every keyframe in the mapper's map).
TEST(SlamSystem, ConcurrentModePosesEveryFrameAndFinishJoinsTheMapper) {
  const SlamRun r = run(/*deterministic=*/false);
  EXPECT_EQ(r.trajectory.size(), kFrames);
  EXPECT_GE(r.stats.keyframes, 3);
  EXPECT_GT(r.stats.points, 200);
  EXPECT_GE(r.stats.maps_applied, 1);
  EXPECT_LT(r.ate_m, 0.004) << "deterministic mode measures 1.4 mm over 300 frames";
}

// A lossy, delayed link between the two ends: every frame posed, within bounds of the
// perfect link, and the same trajectory twice (seeded).
TEST(SlamSystem, DeterministicRunOverALossyLinkIsRepeatable) {
  LinkOptions link;
  link.loss = 0.1, link.delay_ms = 50, link.seed = 3;
  const SlamRun a = run(true, link), b = run(true, link);
  const SlamRun clean = run(true);
  EXPECT_EQ(a.trajectory.size(), kFrames);
  EXPECT_GT(a.stats.link_lost, 0) << "the link lost messages";
  ASSERT_EQ(a.trajectory.size(), b.trajectory.size());
  for (size_t i = 0; i < a.trajectory.size(); ++i) {
    ASSERT_EQ(a.trajectory[i].T_w_c.matrix(), b.trajectory[i].T_w_c.matrix()) << "frame " << i;
  }
  EXPECT_LT(a.ate_m, 2.0 * clean.ate_m + 0.001);
}

}  // namespace
}  // namespace rgbdslam
