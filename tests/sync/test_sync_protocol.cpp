// The whole map protocol over the in-memory link (sync/memory_link.h), with the real parts at
// both ends: TrackerSync and the tracker's MapReplica, MapperSync with a real Mapper and a
// journal kept in memory. No network, no root: loss, delay, outages, duplicates, reordering
// and a mapper restart are all simulated, seeded, on a simulated clock.
#include <gtest/gtest.h>

#include <memory>

#include "rgbdslam/map/map_file.h"
#include "rgbdslam/sync/memory_link.h"
#include "rgbdslam/sync/mapper_sync.h"
#include "rgbdslam/sync/tracker_sync.h"
#include "rgbdslam/tracking/map_replica.h"

namespace rgbdslam {
namespace {

constexpr int64_t kS = 1000000;     // [us]
constexpr int64_t kTick = 50000;    // the simulation's step: 50 ms [us]
constexpr int64_t kMapId = 77;

class MemoryJournal : public KeyframeJournal {
 public:
  Status appendKeyframe(const IncomingKeyframe& k) override {
    keyframes.push_back(k);
    return Status{};
  }
  Status appendVersion(int64_t v) override {
    last_version = v;
    return Status{};
  }
  Status appendCulled(const std::vector<KeyframeId>& ids) override {
    culled.insert(culled.end(), ids.begin(), ids.end());
    return Status{};
  }
  std::vector<IncomingKeyframe> keyframes;
  int64_t last_version = 0;
  std::vector<KeyframeId> culled;
};

PinholeCamera smallCamera() {
  PinholeCamera camera;
  camera.width = 160, camera.height = 120;
  camera.fx = camera.fy = 120.0, camera.cx = 80.0, camera.cy = 60.0;
  return camera;
}

// Keyframe k: 0.1 m further along x, with ten points from depth 2 m ahead (provisional ids)
// and its measurements of the previous keyframe's points.
KeyframeData makeKeyframe(const PinholeCamera& camera, KeyframeId k, bool see_keyframe_one = false) {
  KeyframeData kf;
  kf.utime = k * kS;
  kf.map_id = kMapId;
  kf.id = k;
  kf.T_w_c = SE3(Mat3::Identity(), Vec3(0.1 * k, 0, 0));
  cv::Mat grey(camera.height, camera.width, CV_8UC1);
  cv::randu(grey, 0, 255);
  kf.grey = grey;
  for (int i = 0; i < 10; ++i) {
    const Eigen::Vector2d uv(20.0 + 12.0 * i, 30.0 + 6.0 * i);
    MapPointData p;
    p.id = provisionalPointId(k, i);
    p.source_keyframe = k;
    p.uv = uv;
    p.p_w = kf.T_w_c * camera.unproject(uv, 2.0);
    kf.new_points.push_back(p);
    kf.measurements.push_back(Measurement{p.id, uv, 0, 2.0});
  }
  if (!see_keyframe_one || k < 2) return kf;
  // Keyframe 1's points, seen again: keyframe 1 becomes redundant (map_maintenance.h).
  const SE3 T_one(Mat3::Identity(), Vec3(0.1, 0, 0));
  for (int i = 0; i < 10; ++i) {
    const Vec3 p_w = T_one * camera.unproject(Eigen::Vector2d(20.0 + 12.0 * i, 30.0 + 6.0 * i), 2.0);
    const Vec3 p_c = kf.T_w_c.inverse() * p_w;
    if (const auto uv = camera.project(p_c)) {
      kf.measurements.push_back(Measurement{provisionalPointId(1, i), *uv, 0, p_c.z()});
    }
  }
  return kf;
}

KeyframeOutboxOptions retaining(int retained) {
  KeyframeOutboxOptions o;
  o.retained = retained;
  return o;
}

struct Rig {
  explicit Rig(const LinkOptions& up_link, const LinkOptions& down_link, int retained = 64,
               bool see_keyframe_one = false)
      : camera(smallCamera()), replica(camera), tracker(kMapId, retaining(retained)),
        up(up_link), down(down_link), receipts(up_link), see_keyframe_one(see_keyframe_one) {
    startMapper();
  }

  void startMapper() {
    MapperOptions mapper_options;
    mapper_options.cull.keyframe_cull_min_points = 0;  // these keyframes measure 10-20 points
    mapper_options.cull.keyframe_cull_min_age = 2;
    mapper = std::make_unique<Mapper>(camera, mapper_options, SlamMode::kDepthBa);
    MapperSyncOptions options;
    options.publisher.map_period_s = 0.5;
    sync = std::make_unique<MapperSync>(mapper.get(), options, &journal);
  }

  // A mapper process killed and started again on the same journal.
  void restartMapper() {
    startMapper();
    ASSERT_TRUE(sync->restore(journal.keyframes, journal.last_version, journal.culled));
  }

  // ...on a journal cut short by a corrupt record: only the first 'keep' keyframes and the
  // versions published before the next one was acknowledged survive.
  void restartMapperOnCutJournal(size_t keep) {
    journal.keyframes.resize(keep);
    journal.last_version = keep == 0 ? 0 : published.at(keep - 1);
    startMapper();
    ASSERT_TRUE(sync->restore(journal.keyframes, journal.last_version));
  }

  void createKeyframe() {
    const KeyframeId k = next_keyframe++;
    KeyframeData kf = makeKeyframe(camera, k, see_keyframe_one);
    replica.addKeyframe(rgbdslam::makeKeyframe(kf, KeyframeBuildOptions{}));
    for (size_t i = 0; i < kf.new_points.size(); ++i) {
      NewPoint np;
      np.point = MapPoint(kf.new_points[i]);
      np.measurement = kf.measurements[i];
      replica.addProvisionalPoint(np);
    }
    up.send(kf, now);
    tracker.send(k, kf, now);
  }

  // One tick: the tracker's end, then the mapper's.
  void step(const std::function<bool(const MapUpdate&)>& drop_down = nullptr) {
    now += kTick;
    for (const MapUpdate& u : down.receive(now)) {
      if (drop_down && drop_down(u)) continue;
      const MapReceiveResult r = tracker.receive(u, now, [this](const MapUpdate& m) { return replica.apply(m); });
      verdicts[r.verdict]++;
    }
    for (const KeyframeData* again : tracker.resendsDue(now)) up.send(*again, now);
    if (now % kS == 0) receipts.send(tracker.receipt(now), now);
    for (KeyframeData& kf : up.receive(now)) intake[sync->offer(IncomingKeyframe{std::move(kf), {}})]++;
    for (const MapReceipt& r : receipts.receive(now)) sync->onReceipt(r);
    while (sync->integrateNext()) publish();
    for (int i = 0; i < 3 && sync->refine(); ++i) publish();
    publish();
  }

  void publish() {
    if (auto u = sync->publishDue(now)) {
      published.push_back(u->version);
      down.send(*u, now);
    }
  }

  // Runs until, for a whole second (longer than the publisher's map period, so nothing
  // waits to be published), every keyframe is acknowledged, the mapper has converged and the
  // tracker holds the mapper's newest version; false when 'limit_s' passed first.
  bool settle(double limit_s) {
    const int64_t end = now + static_cast<int64_t>(limit_s * kS);
    int64_t quiet_since = -1;
    while (now < end) {
      step();
      const bool quiet = tracker.outbox().empty() && sync->converged() &&
                         tracker.follower().version() == sync->version() && down.inFlight() == 0;
      if (!quiet) quiet_since = -1;
      else if (quiet_since < 0) quiet_since = now;
      else if (now - quiet_since >= kS) return true;
    }
    return false;
  }

  // The replica agrees with the mapper's map: every keyframe within the publisher's
  // thresholds (1 mm, 0.5 mrad), the same points.
  void expectConsistent() const {
    const Map& truth = mapper->map();
    ASSERT_EQ(truth.numKeyframes() + static_cast<size_t>(mapper->keyframesCulled()), static_cast<size_t>(next_keyframe));
    ASSERT_EQ(replica.map().numKeyframes(), truth.numKeyframes()) << "culled keyframes leave the replica too";
    for (const auto& [id, kf] : truth.keyframes()) {
      const Keyframe* mine = replica.map().keyframe(id);
      ASSERT_NE(mine, nullptr) << id;
      EXPECT_LT((mine->T_w_c.translation() - kf->T_w_c.translation()).norm(), 1.5e-3) << "keyframe " << id;
    }
    EXPECT_EQ(replica.map().numPoints(), truth.numPoints());
    for (const auto& [id, p] : truth.points()) {
      const MapPoint* mine = replica.map().point(id);
      ASSERT_NE(mine, nullptr) << "point " << id;
      EXPECT_LT((mine->p_w - p.p_w).norm(), 1.5e-3) << "point " << id;
    }
  }

  // Creates n keyframes, one every 'every' seconds, stepping in between.
  void fly(int n, double every_s) {
    for (int i = 0; i < n; ++i) {
      createKeyframe();
      for (int64_t t = 0; t < static_cast<int64_t>(every_s * kS); t += kTick) step();
    }
  }

  PinholeCamera camera;
  MapReplica replica;
  TrackerSync<KeyframeData> tracker;
  MemoryLink<KeyframeData> up;
  MemoryLink<MapUpdate> down;
  MemoryLink<MapReceipt> receipts;
  MemoryJournal journal;
  std::unique_ptr<Mapper> mapper;
  std::unique_ptr<MapperSync> sync;
  bool see_keyframe_one = false;
  int64_t now = 0;
  KeyframeId next_keyframe = 0;
  std::vector<int64_t> published;
  std::map<MapVerdict, int> verdicts;
  std::map<IntakeVerdict, int> intake;
};

LinkOptions link(double loss, double delay_ms, uint32_t seed) {
  LinkOptions o;
  o.loss = loss, o.delay_ms = delay_ms, o.seed = seed;
  return o;
}

TEST(SyncProtocol, CleanLinkEveryKeyframeAcknowledgedOnceAndTheReplicaFollows) {
  Rig rig(link(0, 0, 1), link(0, 0, 2));
  rig.fly(12, 0.5);
  ASSERT_TRUE(rig.settle(10));
  rig.expectConsistent();
  EXPECT_EQ(rig.intake[IntakeVerdict::kQueued], 12);
  EXPECT_EQ(rig.intake[IntakeVerdict::kDuplicate], 0) << "no re-sends needed";
  EXPECT_EQ(rig.sync->counters().snapshots_published, 1) << "only the first";
  EXPECT_EQ(rig.verdicts[MapVerdict::kMissingDelta], 0);
}

TEST(SyncProtocol, TenPercentLossEachWayWithFiftyMillisecondDelay) {
  for (uint32_t seed : {1u, 2u, 3u}) {
    Rig rig(link(0.1, 50, seed), link(0.1, 50, seed + 100));
    rig.fly(20, 0.5);
    ASSERT_TRUE(rig.settle(60)) << "seed " << seed;
    rig.expectConsistent();
    EXPECT_EQ(rig.sync->counters().integrated, 20);
    EXPECT_GT(rig.up.lost() + rig.down.lost(), 0) << "the link did lose messages";
    for (size_t i = 1; i < rig.published.size(); ++i) ASSERT_EQ(rig.published[i], rig.published[i - 1] + 1);
  }
}

TEST(SyncProtocol, FiveSecondOutageKeyframesMadeDuringItAreDeliveredAfterwards) {
  LinkOptions up = link(0, 50, 1), down = link(0, 50, 2);
  up.outages_us = down.outages_us = {{3 * kS, 8 * kS}};
  Rig rig(up, down);
  rig.fly(20, 0.5);  // keyframes 6..15 are made during the outage
  ASSERT_TRUE(rig.settle(60));
  rig.expectConsistent();
  EXPECT_GT(rig.up.lost(), 0);
  EXPECT_EQ(rig.sync->counters().integrated, 20);
}

TEST(SyncProtocol, MapperRestartFromItsJournalLosesNothingAndVersionsGoOn) {
  Rig rig(link(0, 50, 1), link(0, 50, 2));
  rig.fly(8, 0.5);
  ASSERT_TRUE(rig.settle(10));
  const int64_t version_before = rig.sync->version();
  ASSERT_EQ(rig.journal.keyframes.size(), 8u);
  rig.restartMapper();  // killed and started again on the same journal
  EXPECT_EQ(rig.sync->counters().restored, 8);
  rig.fly(6, 0.5);
  ASSERT_TRUE(rig.settle(20));
  rig.expectConsistent();
  EXPECT_GT(rig.published.back(), version_before);
  EXPECT_EQ(rig.verdicts[MapVerdict::kStale], 0) << "a restarted mapper never re-uses a version";
}

// Keyframe culling over the link: the tracker's replica loses the culled keyframe with the
// mapper's, the points it described come re-described, and a restarted mapper repeats the
// culls of its journal (else its snapshots would name a keyframe the tracker removed).
TEST(SyncProtocol, CulledKeyframesLeaveTheReplicaAndStayCulledAcrossARestart) {
  Rig rig(link(0.1, 50, 5), link(0.1, 50, 6), 64, /*see_keyframe_one=*/true);
  rig.fly(6, 0.5);
  ASSERT_TRUE(rig.settle(20));
  ASSERT_GE(rig.mapper->keyframesCulled(), 1);
  EXPECT_FALSE(rig.mapper->map().hasKeyframe(1));
  ASSERT_FALSE(rig.journal.culled.empty());
  EXPECT_EQ(rig.journal.culled.front(), 1);
  rig.expectConsistent();
  for (int i = 0; i < 10; ++i) {
    const MapPoint* p = rig.replica.map().point(provisionalPointId(1, i));
    ASSERT_NE(p, nullptr);
    EXPECT_NE(p->source_keyframe, 1);
  }
  rig.restartMapper();
  EXPECT_FALSE(rig.mapper->map().hasKeyframe(1));
  rig.fly(4, 0.5);
  ASSERT_TRUE(rig.settle(20));
  rig.expectConsistent();
}

// Issue 13: a corrupt journal record cut the journal short, acknowledged keyframes were lost,
// and since the tracker never re-sent acknowledged keyframes the mapper waited for ever (and
// its versions, journaled too, went backwards: every map was stale to the tracker).
TEST(SyncProtocol, JournalThatLostAcknowledgedKeyframesGetsThemSentAgain) {
  Rig rig(link(0, 50, 1), link(0, 50, 2));
  rig.fly(10, 0.5);
  ASSERT_TRUE(rig.settle(10));
  const int64_t tracker_version = rig.tracker.follower().version();
  rig.restartMapperOnCutJournal(4);  // keyframes 4..9 and the versions after them are lost
  ASSERT_LT(rig.sync->version(), tracker_version);
  rig.fly(4, 0.5);
  ASSERT_TRUE(rig.settle(30));
  rig.expectConsistent();  // every keyframe, the lost ones included
  const MapperSync::Counters c = rig.sync->counters();
  EXPECT_EQ(c.versions_caught_up, 1);
  EXPECT_EQ(c.keyframes_skipped, 0);
  EXPECT_EQ(c.integrated, 10) << "6 sent again, 4 new";
  EXPECT_EQ(rig.tracker.mapperLosses(), 1);
  EXPECT_GT(rig.tracker.follower().version(), tracker_version);
}

TEST(SyncProtocol, JournalLossBeyondWhatTheTrackerRetainsIsSkippedNotWaitedFor) {
  Rig rig(link(0, 50, 1), link(0, 50, 2), /*retained=*/3);
  rig.fly(10, 0.5);
  ASSERT_TRUE(rig.settle(10));
  rig.restartMapperOnCutJournal(4);  // 4..9 lost; the tracker still holds 7..9
  rig.fly(3, 0.5);
  ASSERT_TRUE(rig.settle(30));
  const MapperSync::Counters c = rig.sync->counters();
  EXPECT_EQ(c.keyframes_skipped, 3) << "keyframes 4, 5 and 6";
  EXPECT_EQ(c.integrated, 6) << "7..9 sent again, 10..12 new";
  const Map& truth = rig.mapper->map();
  EXPECT_EQ(truth.numKeyframes(), 10u);
  for (KeyframeId id : {4, 5, 6}) EXPECT_FALSE(truth.hasKeyframe(id)) << id;
  // The replica's points follow the mapper (the skipped keyframes' points are gone); the
  // tracker keeps its own copies of the skipped keyframes, which no point refers to.
  EXPECT_EQ(rig.replica.map().numPoints(), truth.numPoints());
  for (const auto& [id, point] : rig.replica.map().points()) EXPECT_TRUE(truth.hasKeyframe(point.source_keyframe)) << id;
  EXPECT_TRUE(rig.tracker.outbox().empty());
}

TEST(SyncProtocol, WholeJournalLostTheMapGoesOnFromTheKeyframesThatStillCome) {
  Rig rig(link(0, 50, 1), link(0, 50, 2), /*retained=*/3);
  rig.fly(6, 0.5);
  ASSERT_TRUE(rig.settle(10));
  rig.restartMapperOnCutJournal(0);
  rig.fly(3, 0.5);
  ASSERT_TRUE(rig.settle(30));
  const MapperSync::Counters c = rig.sync->counters();
  EXPECT_EQ(rig.sync->mapId(), kMapId);
  EXPECT_EQ(c.keyframes_skipped, 6);
  EXPECT_EQ(c.integrated, 3);
  EXPECT_EQ(rig.mapper->map().numKeyframes(), 3u);
  EXPECT_EQ(rig.tracker.follower().version(), rig.sync->version());
  EXPECT_EQ(rig.replica.map().numPoints(), rig.mapper->map().numPoints());
  EXPECT_TRUE(rig.tracker.outbox().empty());
}

// Found by the fail-before check: with the default retention the tracker still held
// keyframe 0, so nothing was skipped, and a mapper without a map published nothing that
// would make the tracker send again: it waited for ever.
TEST(SyncProtocol, WholeJournalLostTheTrackerSendsItsRetainedKeyframesAgain) {
  Rig rig(link(0, 50, 1), link(0, 50, 2));
  rig.fly(6, 0.5);
  ASSERT_TRUE(rig.settle(10));
  rig.restartMapperOnCutJournal(0);
  rig.fly(3, 0.5);
  ASSERT_TRUE(rig.settle(30));
  rig.expectConsistent();  // all 9 keyframes
  EXPECT_EQ(rig.sync->counters().keyframes_skipped, 0);
  EXPECT_EQ(rig.sync->counters().integrated, 9);
  EXPECT_EQ(rig.tracker.mapperLosses(), 1);
  EXPECT_EQ(rig.verdicts[MapVerdict::kStale], 0) << "versions went on after the tracker's";
}

TEST(SyncProtocol, DuplicatedAndReorderedKeyframesAreIntegratedOnceInOrder) {
  LinkOptions up = link(0, 20, 5);
  up.jitter_ms = 1500;  // keyframes every 0.3 s arrive out of order
  up.duplicate = 0.3;
  Rig rig(up, link(0, 20, 6));
  rig.fly(20, 0.3);
  ASSERT_TRUE(rig.settle(30));
  rig.expectConsistent();
  const MapperSync::Counters c = rig.sync->counters();
  EXPECT_EQ(c.integrated, 20);
  EXPECT_GT(c.out_of_order, 0);
  EXPECT_GT(c.duplicates, 0);
  KeyframeId expected = 0;
  for (const auto& [id, kf] : rig.mapper->map().keyframes()) EXPECT_EQ(id, expected++);
}

TEST(SyncProtocol, ALostDeltaIsRepairedByASnapshotTheReceiptsAskFor) {
  Rig rig(link(0, 0, 1), link(0, 0, 2));
  rig.fly(4, 0.5);
  ASSERT_TRUE(rig.settle(10));
  rig.createKeyframe();
  bool dropped = false;  // the next delta is lost on the way
  for (int i = 0; i < 10 && !dropped; ++i) {
    rig.step([&dropped](const MapUpdate& u) { return !u.is_snapshot && !dropped && (dropped = true); });
  }
  ASSERT_TRUE(dropped);
  rig.fly(3, 0.5);
  ASSERT_TRUE(rig.settle(10));
  rig.expectConsistent();
  EXPECT_GT(rig.verdicts[MapVerdict::kMissingDelta], 0);
  EXPECT_GE(rig.sync->counters().snapshots_asked, 1);
  EXPECT_EQ(rig.sync->counters().snapshots_published, 2) << "the first, and one for the loss";
}

TEST(SyncIntake, RefusesForeignMapsMapIdZeroAndAFullQueue) {
  const PinholeCamera camera = smallCamera();
  Mapper mapper(camera, MapperOptions{}, SlamMode::kDepthBa);
  MapperSyncOptions options;
  options.max_queued_keyframes = 2;
  MapperSync sync(&mapper, options);
  KeyframeData zero = makeKeyframe(camera, 0);
  zero.map_id = 0;  // no tracker uses map 0: a fresh mapper must not adopt it
  EXPECT_EQ(sync.offer({zero, {}}), IntakeVerdict::kForeignMap);
  EXPECT_EQ(sync.offer({makeKeyframe(camera, 2), {}}), IntakeVerdict::kQueued);
  EXPECT_EQ(sync.offer({makeKeyframe(camera, 3), {}}), IntakeVerdict::kQueued);
  EXPECT_EQ(sync.offer({makeKeyframe(camera, 4), {}}), IntakeVerdict::kQueueFull);
  EXPECT_FALSE(sync.integrateNext()) << "keyframe 0 is missing";
  KeyframeData other = makeKeyframe(camera, 0);
  other.map_id = kMapId + 1;  // keyframe 0 of another map arrives first...
  KeyframeData first = makeKeyframe(camera, 0);
  options.max_queued_keyframes = 64;
  MapperSync fresh(&mapper, options);
  EXPECT_EQ(fresh.offer({other, {}}), IntakeVerdict::kQueued);
  EXPECT_EQ(fresh.offer({first, {}}), IntakeVerdict::kDuplicate) << "one keyframe 0 at a time";
  ASSERT_TRUE(fresh.integrateNext());
  EXPECT_EQ(fresh.mapId(), kMapId + 1);
  EXPECT_EQ(fresh.offer({makeKeyframe(camera, 1), {}}), IntakeVerdict::kForeignMap);
}

// A re-send that arrives while its keyframe is being integrated (here from the journal's
// append, which runs inside integrateNext) is a duplicate. Queued again, it stayed in the
// queue below next_id_ for good and left the interrupt flag set, so refinement never
// converged: SlamSystem's concurrent mapper never finished (seen under ASan, whose slowness
// let the tracker's re-send period pass during an integration).
TEST(SyncIntake, AReSendDuringItsIntegrationIsADuplicate) {
  const PinholeCamera camera = smallCamera();
  Mapper mapper(camera, MapperOptions{}, SlamMode::kDepthBa);
  struct ReSendingJournal : MemoryJournal {
    Status appendKeyframe(const IncomingKeyframe& k) override {
      verdicts.push_back(sync->offer(k));
      return MemoryJournal::appendKeyframe(k);
    }
    MapperSync* sync = nullptr;
    std::vector<IntakeVerdict> verdicts;
  } journal;
  MapperSync sync(&mapper, MapperSyncOptions{}, &journal);
  journal.sync = &sync;
  for (KeyframeId k = 0; k < 2; ++k) {
    ASSERT_EQ(sync.offer({makeKeyframe(camera, k), {}}), IntakeVerdict::kQueued);
    ASSERT_TRUE(sync.integrateNext());
  }
  EXPECT_EQ(journal.verdicts, std::vector<IntakeVerdict>(2, IntakeVerdict::kDuplicate));
  EXPECT_EQ(sync.queueLength(), 0u);
  int refinements = 0;
  while (sync.refine() && refinements < 100) ++refinements;
  EXPECT_TRUE(sync.converged()) << "after " << refinements << " refinements";
}


// rgbd-mapper --load-map FILE --map-id ID, killed and started again with the same flags: its
// journal holds only the keyframes added after the file's, and they are re-integrated on top
// of the file; a journal of another map is refused.
TEST(SyncIntake, AMapperStartedFromAFileRestartsOnTopOfIt) {
  const PinholeCamera camera = smallCamera();
  Mapper saved(camera, MapperOptions{}, SlamMode::kDepthBa);
  MapperSync saved_sync(&saved, MapperSyncOptions{});
  for (KeyframeId k = 0; k < 4; ++k) {
    ASSERT_EQ(saved_sync.offer({makeKeyframe(camera, k), {}}), IntakeVerdict::kQueued);
    ASSERT_TRUE(saved_sync.integrateNext());
  }
  const auto bytes = encodeMapFile(saved.map(), camera, SlamMode::kDepthBa);
  ASSERT_TRUE(bytes) << bytes.error();
  const auto file = decodeMapFile(*bytes, "saved.map");
  ASSERT_TRUE(file) << file.error();
  ASSERT_EQ(file->nextKeyframeId(), 4);

  MemoryJournal journal;
  {  // the first process: the file, then three keyframes of the new session
    Mapper mapper(camera, MapperOptions{}, SlamMode::kDepthBa);
    MapperSync sync(&mapper, MapperSyncOptions{}, &journal);
    mapper.load(*file);
    sync.adopt(kMapId, file->nextKeyframeId());
    EXPECT_EQ(sync.offer({makeKeyframe(camera, 2), {}}), IntakeVerdict::kDuplicate) << "the file's own";
    for (KeyframeId k = 4; k < 7; ++k) {
      ASSERT_EQ(sync.offer({makeKeyframe(camera, k), {}}), IntakeVerdict::kQueued);
      ASSERT_TRUE(sync.integrateNext());
    }
    ASSERT_TRUE(sync.publishDue(kS));
  }
  ASSERT_EQ(journal.keyframes.size(), 3u);
  EXPECT_EQ(journal.keyframes.front().keyframe.id, 4);
  const int64_t last_version = journal.last_version;
  ASSERT_GT(last_version, 0);

  Mapper mapper(camera, MapperOptions{}, SlamMode::kDepthBa);  // restarted with the same flags
  MapperSync sync(&mapper, MapperSyncOptions{}, &journal);
  mapper.load(*file);
  sync.adopt(kMapId, file->nextKeyframeId());
  const Status restored = sync.restore(journal.keyframes, last_version);
  ASSERT_TRUE(restored) << restored.error();
  EXPECT_EQ(sync.counters().restored, 3);
  EXPECT_EQ(mapper.map().numKeyframes(), 7u);
  EXPECT_EQ(sync.mapId(), kMapId);
  EXPECT_EQ(sync.offer({makeKeyframe(camera, 7), {}}), IntakeVerdict::kQueued);
  const auto next = sync.publishDue(2 * kS);
  ASSERT_TRUE(next);
  EXPECT_GT(next->version, last_version) << "versions go on after the journaled ones";

  Mapper other(camera, MapperOptions{}, SlamMode::kDepthBa);  // the journal of map 77 as map 78
  MapperSync other_sync(&other, MapperSyncOptions{});
  other.load(*file);
  other_sync.adopt(kMapId + 1, file->nextKeyframeId());
  EXPECT_FALSE(other_sync.restore(journal.keyframes, last_version));
}

}  // namespace
}  // namespace rgbdslam
