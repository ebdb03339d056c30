// The tracker's link budget: the token bucket's average rate over a long run, and the ladder
// of keyframe encodings on a rendered keyframe (real JPEG and zlib, real sizes).
#include "common/link_budget.h"

#include <gtest/gtest.h>

#include "rgbdslam/synth/scene.h"
#include "sample_messages.h"

namespace rgbdslam {
namespace {

constexpr int64_t kSecondUs = 1000000;

// A sender that publishes a message of 'message_bytes' whenever the bucket is open, polled
// every 10 ms for 'seconds': what it sent in all [bytes].
int64_t greedySend(LinkBudget* budget, size_t message_bytes, int seconds) {
  for (int64_t t = 0; t <= seconds * kSecondUs; t += 10000) {
    budget->refill(t);
    while (budget->open()) budget->spend(message_bytes);
  }
  return budget->bytesSent();
}

TEST(LinkBudget, AGreedySenderGetsTheBudgetAndNoMore) {
  LinkBudgetOptions options;
  options.kbps = 1000;
  options.burst_s = 2;
  LinkBudget budget(options);
  const size_t message = 40000;  // a keyframe at the best rung
  const int64_t sent = greedySend(&budget, message, 60);
  const double allowed = 1000 * 1000 / 8.0 * 60 + 1000 * 1000 / 8.0 * 2 + message;  // rate, burst, one overdraw
  EXPECT_LE(sent, allowed);
  EXPECT_GE(sent, allowed - 2 * message);  // and it is not held below the budget
  EXPECT_LT(budget.fill(), 0.5);
}

TEST(LinkBudget, NoBudgetIsAlwaysOpenAndFull) {
  LinkBudgetOptions options;
  options.kbps = 0;
  LinkBudget budget(options);
  budget.refill(0);
  budget.spend(1 << 30);
  EXPECT_TRUE(budget.open());
  EXPECT_DOUBLE_EQ(budget.fill(), 1.0);
  EXPECT_EQ(budget.bytesSent(), int64_t{1} << 30);
}

TEST(LinkBudget, TheBucketRefillsAtTheRateUpToItsBurst) {
  LinkBudgetOptions options;
  options.kbps = 800;  // 100 kB/s
  options.burst_s = 1;
  LinkBudget budget(options);
  budget.refill(0);
  budget.spend(150000);  // overdrawn by 50 kB
  EXPECT_FALSE(budget.open());
  EXPECT_NEAR(budget.fill(), -0.5, 1e-9);
  budget.refill(kSecondUs / 4);  // +25 kB
  EXPECT_FALSE(budget.open());
  budget.refill(kSecondUs);  // +75 kB more: 50 kB
  EXPECT_TRUE(budget.open());
  EXPECT_NEAR(budget.fill(), 0.5, 1e-9);
  budget.refill(100 * kSecondUs);
  EXPECT_NEAR(budget.fill(), 1.0, 1e-9);
  budget.refill(kSecondUs);  // a clock going back adds nothing
  EXPECT_NEAR(budget.fill(), 1.0, 1e-9);
}

TEST(LinkBudget, DebtStopsAtTheCapacitySoQualityComesBack) {
  LinkBudgetOptions options;
  options.kbps = 800;  // 100 kB/s
  options.burst_s = 1;
  LinkBudget budget(options);
  budget.refill(0);
  for (int i = 0; i < 100; ++i) budget.spend(100000);  // 10 MB forced through
  EXPECT_DOUBLE_EQ(budget.fill(), -1.0);
  EXPECT_EQ(budget.bytesSent(), 10000000);
  budget.refill(2 * kSecondUs + 1);  // two bursts' time pays the deepest debt
  EXPECT_TRUE(budget.open());
}

// A half-duplex radio: the maps the tracker receives take from the same bucket, unless the
// option says the link has a direction for each.
TEST(LinkBudget, ReceivedMapsCountWhenTheLinkIsShared) {
  LinkBudgetOptions options;
  options.kbps = 8;  // 1000 bytes a second
  options.burst_s = 1.0;
  LinkBudget shared(options);
  shared.refill(0);
  shared.received(500);
  EXPECT_DOUBLE_EQ(shared.fill(), 0.5);
  EXPECT_EQ(shared.bytesReceived(), 500);
  EXPECT_EQ(shared.bytesSent(), 0);
  options.counts_received = false;
  LinkBudget both_ways(options);
  both_ways.refill(0);
  both_ways.received(500);
  EXPECT_DOUBLE_EQ(both_ways.fill(), 1.0);
  EXPECT_EQ(both_ways.bytesReceived(), 500);
}

TEST(EncodingLadder, RungsFollowTheBucket) {
  EXPECT_EQ(ladderRung(1.0, 4), 0);
  EXPECT_EQ(ladderRung(0.5, 4), 0);
  EXPECT_EQ(ladderRung(0.4, 4), 1);
  EXPECT_EQ(ladderRung(0.2, 4), 2);
  EXPECT_EQ(ladderRung(0.0, 4), 3);
  EXPECT_EQ(ladderRung(-3.0, 4), 3);
  EXPECT_EQ(ladderRung(0.0, 1), 0);
}

TEST(EncodingLadder, StartsAtTheConfiguredEncodingAndEndsAtTheLowestQuality) {
  const auto ladder = encodingLadder(KeyframeEncoding{false, 90, 1}, 30);
  // PNG full, PNG quarter depth, then depth near corners only, JPEG 90, 75, 60, 45, 30, then depth 8
  ASSERT_EQ(ladder.size(), 9u);
  EXPECT_FALSE(ladder[0].jpeg_grey);
  EXPECT_EQ(ladder[0].depth_step, 1);
  EXPECT_EQ(ladder[1].depth_step, 4);
  EXPECT_FALSE(ladder[1].depth_near_corners);
  EXPECT_TRUE(ladder[2].depth_near_corners);
  EXPECT_FALSE(ladder[2].jpeg_grey);
  EXPECT_TRUE(ladder[3].jpeg_grey);
  for (size_t i = 2; i < ladder.size(); ++i) EXPECT_TRUE(ladder[i].depth_near_corners) << i;
  EXPECT_EQ(ladder.back().jpeg_quality, 30);
  EXPECT_EQ(ladder.back().depth_step, 8);
  EXPECT_EQ(ladder[ladder.size() - 2].depth_step, 4);
  const auto from_default = encodingLadder(KeyframeEncoding{true, 75, 4}, 30);
  ASSERT_EQ(from_default.size(), 6u);  // 75, 75 with depth near corners, 60, 45, 30, 30 with depth 8
  EXPECT_EQ(from_default[1].jpeg_quality, 75);
  EXPECT_TRUE(from_default[1].depth_near_corners);
  EXPECT_EQ(from_default[2].jpeg_quality, 60);
  EXPECT_EQ(encodingLadder(KeyframeEncoding{true, 20, 4}, 30).size(), 3u);  // below the floor: corners, depth 8
  KeyframeEncoding coarsest{true, 20, 8};
  coarsest.depth_near_corners = true;
  EXPECT_EQ(encodingLadder(coarsest, 30).size(), 1u);  // nothing coarser
  const auto high_floor = encodingLadder(KeyframeEncoding{false, 90, 4}, 95);  // PNG, corners, JPEG 95, depth 8
  ASSERT_EQ(high_floor.size(), 4u);
  EXPECT_EQ(high_floor[2].jpeg_quality, 95);
}

TEST(EncodingLadder, EachRungOfARenderedKeyframeIsNoLargerAndDecodes) {
  const SyntheticScene scene(*parseSyntheticSpec("room,frames=2"));
  const RgbdFrame frame = scene.render(0);
  KeyframeData keyframe;
  keyframe.id = 0;
  keyframe.map_id = 1;
  keyframe.grey = frame.grey();
  keyframe.depth = frame.depth;
  keyframe.depth_scale = frame.depth_scale;
  size_t previous = SIZE_MAX, first = 0;
  bool near_corners = false;
  for (const KeyframeEncoding& rung : encodingLadder(KeyframeEncoding{true, 75, 2}, 30)) {
    const auto bytes = test::encode(toLcm(keyframe, rung));
    if (rung.depth_near_corners && !near_corners) {
      // The room is textured all over: the mask keeps nearly everything, and the whole
      // depth goes when it is no larger (the corridor's plain walls: test_lcm_conversions).
      EXPECT_LE(bytes.size(), previous);
      near_corners = true;
    } else {
      EXPECT_LT(bytes.size(), previous) << "quality " << rung.jpeg_quality << ", depth step " << rung.depth_step;
    }
    if (first == 0) first = bytes.size();
    previous = bytes.size();
    auto msg = decodeMessage<rgbdslam::keyframe_t>(bytes.data(), bytes.size());
    ASSERT_TRUE(msg) << msg.error();
    auto back = fromLcm(*msg);
    ASSERT_TRUE(back) << back.error();
    EXPECT_EQ(back->grey.size(), keyframe.grey.size());
  }
  EXPECT_LT(previous, first * 7 / 10);  // the last rung saves at least 30 %
}

}  // namespace
}  // namespace rgbdslam
