// The map protocol's parts one at a time: the tracker's outbox and follower, the mapper's
// publisher and intake. The whole loop over a lossy link: test_sync_protocol.cpp.
#include <gtest/gtest.h>

#include "rgbdslam/sync/keyframe_outbox.h"
#include "rgbdslam/sync/map_follower.h"
#include "rgbdslam/sync/map_publisher.h"
#include "rgbdslam/sync/memory_link.h"
#include "rgbdslam/sync/tracker_sync.h"

namespace rgbdslam {
namespace {

constexpr int64_t kS = 1000000;  // one second [us]

TEST(SyncOutbox, ResendsWithDoublingIntervalOldestFirstUntilAcknowledged) {
  KeyframeOutbox<int> outbox(KeyframeOutboxOptions{1.0, 4.0, 2});
  outbox.sent(0, 100, 0);
  outbox.sent(1, 101, 0);
  outbox.sent(2, 102, 0);
  EXPECT_TRUE(outbox.resendsDue(kS - 1).empty());
  auto due = outbox.resendsDue(kS);  // the oldest two
  ASSERT_EQ(due.size(), 2u);
  EXPECT_EQ(*due[0], 100);
  EXPECT_EQ(*due[1], 101);
  EXPECT_TRUE(outbox.resendsDue(kS).empty()) << "keyframe 2 waits for the oldest two";
  EXPECT_TRUE(outbox.resendsDue(3 * kS - 1).empty());  // next after 2 s (doubled)
  EXPECT_EQ(outbox.resendsDue(3 * kS).size(), 2u);
  EXPECT_EQ(outbox.sends(0), 3);
  EXPECT_EQ(outbox.sends(2), 1);
  const std::vector<double> ages = outbox.acknowledgeBelow(1, 3 * kS + kS / 2);
  ASSERT_EQ(ages.size(), 1u);
  EXPECT_DOUBLE_EQ(ages[0], 3.5);
  EXPECT_EQ(outbox.size(), 2u);
  due = outbox.resendsDue(3 * kS + kS / 2);  // keyframe 2's turn: at once, long due
  ASSERT_EQ(due.size(), 1u);
  EXPECT_EQ(*due[0], 102);
  // The interval stops growing at resend_max_period_s (4 s): 1, 2, 4, 4, ...
  int64_t t = 3 * kS;
  for (int i = 0; i < 3; ++i) {
    t += 4 * kS;
    EXPECT_FALSE(outbox.resendsDue(t).empty()) << "re-send " << i;
  }
}

// A link outage of five minutes with a keyframe made every second: the re-sends stay at
// two keyframes per 4 s, however many wait (before: every waiting keyframe each 4 s).
TEST(SyncOutbox, AnOutageCostsTheOldestTwoKeyframesNotAllThatWait) {
  KeyframeOutbox<int> outbox(KeyframeOutboxOptions{1.0, 4.0, 2});
  int resent = 0;
  for (int64_t t_ms = 0; t_ms <= 300000; t_ms += 10) {
    if (t_ms % 1000 == 0) outbox.sent(static_cast<KeyframeId>(t_ms / 1000), 0, t_ms * 1000);
    resent += static_cast<int>(outbox.resendsDue(t_ms * 1000).size());
  }
  EXPECT_EQ(outbox.size(), 301u);
  EXPECT_LE(resent, 2 * (300 / 4 + 3));
  EXPECT_GE(resent, 2 * (300 / 4 - 3)) << "the oldest keep being re-sent";
  EXPECT_EQ(outbox.sends(2), 1) << "the third oldest was never re-sent";
}

TEST(SyncOutbox, RetainsTheNewestAcknowledgedForAMapperThatLosesThem) {
  KeyframeOutboxOptions options{1.0, 4.0, 2};
  options.retained = 2;
  KeyframeOutbox<int> outbox(options);
  for (int id = 0; id < 4; ++id) outbox.sent(id, 100 + id, 0);
  outbox.acknowledgeBelow(4, kS / 2);
  EXPECT_TRUE(outbox.empty());
  EXPECT_EQ(outbox.oldestSendable(4), 2) << "keyframes 0 and 1 are gone for good";
  EXPECT_EQ(outbox.resendFrom(1, kS), 2);  // the mapper lost keyframes 1 on
  auto due = outbox.resendsDue(kS);         // at once, oldest first
  ASSERT_EQ(due.size(), 2u);
  EXPECT_EQ(*due[0], 102);
  EXPECT_EQ(*due[1], 103);
  EXPECT_EQ(outbox.oldestSendable(4), 2);
  outbox.acknowledgeBelow(4, 2 * kS);
  EXPECT_EQ(outbox.oldestSendable(4), 2) << "retained again";
  options.retained = 0;
  KeyframeOutbox<int> none(options);
  none.sent(0, 100, 0);
  none.acknowledgeBelow(1, kS);
  EXPECT_EQ(none.oldestSendable(1), 1);
  EXPECT_EQ(none.resendFrom(0, kS), 0);
}

MapUpdate update(int64_t map_id, int64_t version, bool snapshot) {
  MapUpdate u;
  u.map_id = map_id;
  u.version = version;
  u.is_snapshot = snapshot;
  return u;
}

TEST(SyncFollower, AppliesInOrderNeverBackwardsAndWaitsForASnapshotAfterAGap) {
  MapFollower follower(7);
  EXPECT_EQ(follower.judge(update(8, 1, true)), MapVerdict::kForeignMap);
  ASSERT_EQ(follower.judge(update(7, 1, true)), MapVerdict::kApply);
  follower.applied(update(7, 1, true));
  EXPECT_EQ(follower.judge(update(7, 1, false)), MapVerdict::kStale);
  ASSERT_EQ(follower.judge(update(7, 2, false)), MapVerdict::kApply);
  follower.applied(update(7, 2, false));
  EXPECT_EQ(follower.judge(update(7, 4, false)), MapVerdict::kMissingDelta);  // 3 was lost
  EXPECT_EQ(follower.version(), 2);
  EXPECT_EQ(follower.newestSeen(), 4);
  const MapReceipt r = follower.receipt(5, 3, 1);
  EXPECT_EQ(r.applied_version, 2);
  EXPECT_EQ(r.newest_version_seen, 4);
  ASSERT_EQ(follower.judge(update(7, 5, true)), MapVerdict::kApply);  // the snapshot repairs it
  follower.applied(update(7, 5, true));
  EXPECT_EQ(follower.version(), 5);
  // A forged version far ahead would freeze the tracker: refused, and not noted as seen.
  EXPECT_EQ(follower.judge(update(7, int64_t{1} << 62, true)), MapVerdict::kImplausible);
  EXPECT_EQ(follower.newestSeen(), 5);
  EXPECT_EQ(follower.judge(update(7, 6, false)), MapVerdict::kApply);
}

// A map of one keyframe and two points, and the changes that made it.
struct SmallMap {
  Map map;
  MapChanges changes;
  SmallMap() {
    KeyframeData data;
    data.id = 0;
    data.grey = cv::Mat(48, 64, CV_8UC1, cv::Scalar(128));
    map.addKeyframe(makeKeyframe(data, KeyframeBuildOptions{}));
    for (PointId id : {1, 2}) {
      MapPoint p;
      p.id = id;
      p.p_w = Vec3(0, 0, 1.0 + id);
      p.source_keyframe = 0;
      map.addPoint(p);
      changes.points.insert(id);
    }
    changes.keyframes.insert(0);
  }
};

// Review finding: one forged map acknowledging far ahead emptied the outbox and marked every
// provisional keyframe acknowledged for good.
TEST(SyncTracker, AMapAcknowledgingKeyframesNeverSentIsImplausible) {
  TrackerSync<int> tracker(9, KeyframeOutboxOptions{});
  for (KeyframeId id = 0; id < 3; ++id) tracker.send(id, 100 + static_cast<int>(id), 0);
  MapUpdate forged;
  forged.map_id = 9, forged.version = 1, forged.is_snapshot = true, forged.acked_below = 1000;
  bool applied = false;
  const auto r = tracker.receive(forged, kS, [&](const MapUpdate&) { return applied = true; });
  EXPECT_EQ(r.verdict, MapVerdict::kImplausible);
  EXPECT_FALSE(applied);
  EXPECT_EQ(tracker.outbox().size(), 3u) << "nothing acknowledged";
  MapUpdate genuine = forged;
  genuine.acked_below = 3;
  EXPECT_EQ(tracker.receive(genuine, kS, [](const MapUpdate&) { return true; }).verdict, MapVerdict::kApply);
  EXPECT_TRUE(tracker.outbox().empty());
}

TEST(SyncPublisher, SnapshotFirstThenDeltasAtOnceForKeyframesAndRateLimitedForRefinement) {
  SmallMap m;
  MapPublisher publisher(MapPublisherOptions{1.0, 30.0, {}});
  EXPECT_FALSE(publisher.publishDue(m.map, 1, 0)) << "not started: no map id yet";
  publisher.start(9, 0);
  publisher.note(m.changes, /*integrated=*/true);
  auto first = publisher.publishDue(m.map, 1, 0);
  ASSERT_TRUE(first);
  EXPECT_TRUE(first->is_snapshot);
  EXPECT_EQ(first->version, 1);
  EXPECT_EQ(first->map_id, 9);
  EXPECT_EQ(first->acked_below, 1);
  EXPECT_EQ(first->points.size(), 2u);
  EXPECT_FALSE(publisher.publishDue(m.map, 1, kS / 10)) << "nothing new";
  m.map.point(1)->p_w.x() += 0.01;
  MapChanges moved;
  moved.points = {1};
  publisher.note(moved, false);
  EXPECT_FALSE(publisher.publishDue(m.map, 1, kS / 2)) << "refinement waits for map_period_s";
  auto delta = publisher.publishDue(m.map, 1, kS);
  ASSERT_TRUE(delta);
  EXPECT_FALSE(delta->is_snapshot);
  EXPECT_EQ(delta->version, 2);
  ASSERT_EQ(delta->moved_points.size(), 1u);
  publisher.note(MapChanges{}, /*integrated=*/true);  // a new keyframe goes out at once
  EXPECT_TRUE(publisher.publishDue(m.map, 2, kS + 1));
  auto periodic = publisher.publishDue(m.map, 2, 31 * kS);
  ASSERT_TRUE(periodic);
  EXPECT_TRUE(periodic->is_snapshot) << "every snapshot_period_s";
}

// The fallback snapshot is for a tracker that may be out of step: receipts showing it in
// step during the period skip it; without receipts (or with a stuck tracker) it goes.
TEST(SyncPublisher, TheFallbackSnapshotWaitsWhileReceiptsShowTheTrackerInStep) {
  SmallMap m;
  MapPublisher publisher(MapPublisherOptions{1.0, 30.0, {}});
  publisher.start(9, 0);
  publisher.note(m.changes, /*integrated=*/true);
  ASSERT_TRUE(publisher.publishDue(m.map, 1, 0)->is_snapshot);  // version 1
  MapReceipt in_step;
  in_step.map_id = 9;
  in_step.applied_version = in_step.newest_version_seen = 1;
  EXPECT_EQ(publisher.onReceipt(in_step), ReceiptVerdict::kNoted);
  publisher.note(m.changes, /*integrated=*/true);
  auto delta = publisher.publishDue(m.map, 1, 31 * kS);
  ASSERT_TRUE(delta);
  EXPECT_FALSE(delta->is_snapshot) << "the tracker was in step";
  EXPECT_EQ(publisher.snapshotsSkipped(), 1);
  // No receipt during the next period: the fallback goes.
  publisher.note(m.changes, /*integrated=*/true);
  auto fallback = publisher.publishDue(m.map, 1, 62 * kS);
  ASSERT_TRUE(fallback);
  EXPECT_TRUE(fallback->is_snapshot);
  // A receipt that saw a version it could not apply is not in step.
  MapReceipt behind;
  behind.map_id = 9;
  behind.applied_version = 2;
  behind.newest_version_seen = 3;
  publisher.onReceipt(behind);
  publisher.note(m.changes, /*integrated=*/true);
  auto next = publisher.publishDue(m.map, 1, 93 * kS);
  ASSERT_TRUE(next);
  EXPECT_TRUE(next->is_snapshot);
}

// Keyframes faster than map_period_s: each goes out at once with its new points, while the
// moves of points already published wait for the next refinement and go out once.
TEST(SyncPublisher, MovesBetweenKeyframesWaitForTheRefinementPeriod) {
  SmallMap m;
  MapPublisher publisher(MapPublisherOptions{1.0, 30.0, {}});
  publisher.start(9, 0);
  publisher.note(m.changes, /*integrated=*/true);
  ASSERT_TRUE(publisher.publishDue(m.map, 1, 0));  // the snapshot
  MapPoint fresh;
  fresh.id = 3, fresh.p_w = Vec3(0, 0, 3), fresh.source_keyframe = 0;
  m.map.addPoint(fresh);
  m.map.point(1)->p_w.x() += 0.004;  // 4 mm: above the threshold, below ten of them
  MapChanges second;
  second.points = {1, 3};
  publisher.note(second, /*integrated=*/true);
  auto keyframe = publisher.publishDue(m.map, 2, kS / 5);
  ASSERT_TRUE(keyframe) << "a new keyframe goes out at once";
  ASSERT_EQ(keyframe->points.size(), 1u);
  EXPECT_EQ(keyframe->points[0].id, 3);
  EXPECT_TRUE(keyframe->moved_points.empty()) << "the move waits";
  m.map.point(1)->p_w.x() += 0.004;  // moved again before the refinement
  publisher.note(second, /*integrated=*/true);
  auto next = publisher.publishDue(m.map, 3, kS / 2);
  ASSERT_TRUE(next);
  EXPECT_TRUE(next->points.empty() && next->moved_points.empty());
  EXPECT_FALSE(publisher.publishDue(m.map, 3, kS - 1));
  auto refinement = publisher.publishDue(m.map, 3, kS);
  ASSERT_TRUE(refinement) << "the held moves are due after map_period_s";
  ASSERT_EQ(refinement->moved_points.size(), 1u);
  EXPECT_EQ(refinement->moved_points[0].id, 1);
  EXPECT_DOUBLE_EQ(refinement->moved_points[0].p_w.x(), 0.008) << "once, at its latest position";
  EXPECT_FALSE(publisher.publishDue(m.map, 3, 3 * kS)) << "nothing is left";
  // A correction of more than ten thresholds (a loop closure) is not held.
  m.map.point(2)->p_w.y() += 0.05;
  MapChanges closure;
  closure.points = {2};
  publisher.note(closure, /*integrated=*/true);
  auto corrected = publisher.publishDue(m.map, 4, 3 * kS + 1);
  ASSERT_TRUE(corrected);
  ASSERT_EQ(corrected->moved_points.size(), 1u);
  EXPECT_EQ(corrected->moved_points[0].id, 2);
}

TEST(SyncPublisher, ReceiptsShowingAStuckTrackerBringASnapshot) {
  SmallMap m;
  MapPublisher publisher(MapPublisherOptions{0.0, 1000.0, {}});
  publisher.start(9, 0);
  for (int64_t v = 1; v <= 4; ++v) {
    publisher.note(m.changes, true);
    ASSERT_TRUE(publisher.publishDue(m.map, 1, v * kS));
  }
  MapReceipt r;
  r.map_id = 9;
  r.applied_version = 2;
  r.newest_version_seen = 4;  // 3 was lost: 4 could not be applied
  EXPECT_EQ(publisher.onReceipt(r), ReceiptVerdict::kSnapshotAsked);
  auto snapshot = publisher.publishDue(m.map, 1, 5 * kS);
  ASSERT_TRUE(snapshot);
  EXPECT_TRUE(snapshot->is_snapshot);
  EXPECT_EQ(snapshot->version, 5);
  // Receipts sent before the snapshot arrived ask for nothing at first...
  for (int i = 0; i < 3; ++i) EXPECT_EQ(publisher.onReceipt(r), ReceiptVerdict::kNoted) << i;
  // ...but a snapshot that never arrives is sent again.
  EXPECT_EQ(publisher.onReceipt(r), ReceiptVerdict::kSnapshotAsked);
  ASSERT_TRUE(publisher.publishDue(m.map, 1, 5 * kS + 1)->is_snapshot);  // version 6
  // The last delta lost and nothing after it: two receipts in a row with the same version.
  publisher.note(m.changes, true);
  ASSERT_TRUE(publisher.publishDue(m.map, 1, 6 * kS));  // version 7, lost
  r.applied_version = r.newest_version_seen = 6;
  EXPECT_EQ(publisher.onReceipt(r), ReceiptVerdict::kNoted);
  EXPECT_EQ(publisher.onReceipt(r), ReceiptVerdict::kSnapshotAsked);
  // A receipt for another map, or for a version further ahead than a tracker accepts, is
  // refused.
  r.map_id = 10;
  EXPECT_EQ(publisher.onReceipt(r), ReceiptVerdict::kForeignMap);
  r.map_id = 9;
  r.applied_version = r.newest_version_seen = 7 + MapFollower::kDefaultMaxVersionStep + 1;
  EXPECT_EQ(publisher.onReceipt(r), ReceiptVerdict::kImplausible);
  EXPECT_EQ(publisher.version(), 7);
  EXPECT_EQ(publisher.snapshotsAsked(), 3);
  // A version never published, within reach: the tracker holds versions of a mapper run
  // whose journal lost them. Versions go on after it, with a snapshot.
  r.applied_version = r.newest_version_seen = 99;
  EXPECT_EQ(publisher.onReceipt(r), ReceiptVerdict::kCaughtUp);
  auto after = publisher.publishDue(m.map, 1, 7 * kS);
  ASSERT_TRUE(after);
  EXPECT_TRUE(after->is_snapshot);
  EXPECT_EQ(after->version, 100);
  EXPECT_EQ(publisher.versionsCaughtUp(), 1);
}

// A version published just before a receipt is not yet a sign of a stuck tracker: it may be
// on its way, or waiting behind a frame. Only a receipt period later, still not applied, it is.
TEST(SyncPublisher, AVersionPublishedJustBeforeAReceiptIsNotTakenForALostOne) {
  SmallMap m;
  MapPublisher publisher(MapPublisherOptions{0.0, 1000.0, {}});
  publisher.start(9, 0);
  for (int64_t v = 1; v <= 3; ++v) {
    publisher.note(m.changes, true);
    ASSERT_TRUE(publisher.publishDue(m.map, 1, v * kS));
  }
  MapReceipt r;
  r.map_id = 9;
  r.applied_version = r.newest_version_seen = 3;  // in step
  EXPECT_EQ(publisher.onReceipt(r), ReceiptVerdict::kNoted);
  publisher.note(m.changes, true);
  ASSERT_TRUE(publisher.publishDue(m.map, 1, 4 * kS));  // version 4, a moment before the next receipt
  EXPECT_EQ(publisher.onReceipt(r), ReceiptVerdict::kNoted) << "version 4 may be on its way";
  EXPECT_EQ(publisher.onReceipt(r), ReceiptVerdict::kSnapshotAsked) << "a receipt period later: lost";
  EXPECT_EQ(publisher.snapshotsAsked(), 1);
}

TEST(SyncLink, LosesDelaysDuplicatesAndReordersRepeatably) {
  LinkOptions options;
  options.loss = 0.1;
  options.delay_ms = 50;
  options.jitter_ms = 30;
  options.duplicate = 0.1;
  options.seed = 4;
  options.outages_us = {{10 * kS, 11 * kS}};
  auto run = [&options] {
    MemoryLink<int> link(options);
    std::vector<int> got;
    for (int i = 0; i < 2000; ++i) {
      const int64_t t = i * 10000;  // every 10 ms for 20 s
      link.send(i, t);
      for (int m : link.receive(t)) got.push_back(m);
    }
    for (int m : link.receive(100 * kS)) got.push_back(m);
    return std::make_pair(got, link.lost());
  };
  const auto [a, lost] = run();
  const auto [b, lost_b] = run();
  EXPECT_EQ(a, b) << "seeded: the same deliveries";
  const double loss = static_cast<double>(lost - 100) / 1900;  // 100 sends in the outage
  EXPECT_NEAR(loss, 0.1, 0.03);
  int reordered = 0, duplicated = 0, in_outage = 0;
  for (size_t i = 1; i < a.size(); ++i) {
    reordered += a[i] < a[i - 1];
    duplicated += a[i] == a[i - 1];
  }
  for (int m : a) in_outage += m >= 1000 && m < 1100;
  EXPECT_GT(reordered, 50);
  EXPECT_GT(duplicated, 50);
  EXPECT_EQ(in_outage, 0);
}

}  // namespace
}  // namespace rgbdslam
