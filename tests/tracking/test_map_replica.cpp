// The tracker's local map (MapReplica::updateLocalMap): which keyframes keep their pyramid,
// what a cold keyframe keeps, and that a thawed one comes back as it was (up to JPEG).
#include "rgbdslam/tracking/map_replica.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <map>

#include <opencv2/imgproc.hpp>

#include "rgbdslam/synth/scene.h"

namespace rgbdslam {
namespace {

class LocalMap : public ::testing::Test {
 protected:
  void SetUp() override {
    const SyntheticScene scene(*parseSyntheticSpec("room,frames=90"));
    camera = scene.camera();
    replica = std::make_unique<MapReplica>(camera);
    for (KeyframeId id = 0; id < 3; ++id) {
      const RgbdFrame frame = scene.render(static_cast<size_t>(30 * id));
      KeyframeData data;
      data.id = id;
      data.T_w_c = SE3(Mat3::Identity(), Vec3(static_cast<double>(id), 0, 0));  // 1 m apart
      cv::cvtColor(frame.colour, data.grey, cv::COLOR_BGR2GRAY);
      originals.push_back(data.grey.clone());
      replica->addKeyframe(makeKeyframe(data, KeyframeBuildOptions{}));
      NewPoint point;
      point.point = MapPoint(MapPointData{100 + id, Vec3(static_cast<double>(id), 0, 2), id,
                                          Eigen::Vector2d(320, 240), 0});
      point.measurement = Measurement{100 + id, Eigen::Vector2d(320, 240), 0, 2.0};
      replica->addProvisionalPoint(point);
    }
  }
  const Keyframe& keyframe(KeyframeId id) const { return *replica->map().keyframe(id); }
  static MapUpdate removal(int64_t version, std::vector<PointId> points, std::vector<KeyframeId> keyframes) {
    MapUpdate update;
    update.version = version;
    update.removed_points = std::move(points);
    update.removed_keyframes = std::move(keyframes);
    return update;
  }
  // Map version 1 acknowledges the three keyframes (the mapper may cull them now).
  void acknowledgeAll() { acknowledgeAll(replica.get()); }
  static void acknowledgeAll(MapReplica* r) {
    MapUpdate acked;
    acked.version = 1;
    acked.acked_below = 3;
    ASSERT_TRUE(r->apply(acked));
  }
  // A second replica built as 'replica' is.
  std::unique_ptr<MapReplica> anotherReplica() {
    auto other = std::make_unique<MapReplica>(camera);
    std::swap(other, replica);
    SetUp();
    std::swap(other, replica);
    return other;
  }

  PinholeCamera camera;
  std::unique_ptr<MapReplica> replica;
  std::vector<cv::Mat> originals;
};

TEST_F(LocalMap, KeyframesOutsideTheWindowGoColdAndTheirPointsAreNotSearched) {
  const LocalMapChange change = replica->updateLocalMap({0}, 2, 10, 90);
  EXPECT_EQ(change.frozen, 2);
  EXPECT_EQ(replica->hotKeyframes(), 1);
  EXPECT_FALSE(keyframe(0).cold());
  for (KeyframeId id : {1, 2}) {
    EXPECT_TRUE(keyframe(id).cold());
    EXPECT_GT(keyframe(id).cold_grey.size(), 1000u);
    EXPECT_LT(keyframe(id).cold_grey.size(), originals[id].total() / 2) << "JPEG, not raw";
  }
  std::vector<KeyframeView> views;
  makeKeyframeViews(replica->map(), SE3(), &views);
  ASSERT_EQ(views.size(), 3u);
  EXPECT_TRUE(views[0].valid);
  EXPECT_FALSE(views[1].valid);
  EXPECT_FALSE(views[2].valid);
  EXPECT_EQ(replica->map().numPoints(), 3u) << "cold keyframes keep their points";
  // ...but not their slots: only keyframe 0's point is searched.
  ASSERT_EQ(replica->slots().size(), 1u);
  EXPECT_EQ(replica->slots()[0].point->id, 100);
  // From keyframe 1's pose all three points are in the image: the cold keyframes' points
  // count as in view (the tracker thaws those first), and the hot one's slot projects.
  const SE3 T_c_w = keyframe(1).T_c_w();
  makeKeyframeViews(replica->map(), T_c_w, &views);
  EXPECT_TRUE(projectPoint(camera, T_c_w, views, ProjectionOptions{}, &replica->slots()[0]));
  for (const auto& [id, point] : replica->map().points()) {
    EXPECT_TRUE(inView(camera, T_c_w, point.p_w, ProjectionOptions{})) << "point " << id;
  }
  EXPECT_FALSE(inView(camera, T_c_w, Vec3(1, 0, -2), ProjectionOptions{})) << "behind the camera";
  EXPECT_FALSE(inView(camera, T_c_w, Vec3(5, 0, 2), ProjectionOptions{})) << "outside the image";
}

// A point's depth record lives with the point, so it survives its slot: a keyframe that goes
// cold and comes back has its points searched again with the record they had.
TEST_F(LocalMap, APointKeepsItsDepthRecordWhileItsKeyframeIsCold) {
  for (int i = 0; i < 3; ++i) replica->slots()[2].point->depth_record.add(DepthVerdict::kAgrees, 2.0);
  ASSERT_EQ(replica->slots()[2].point->id, 102);
  replica->updateLocalMap({0}, 2, 10, 90);
  ASSERT_EQ(replica->slots().size(), 1u);
  replica->updateLocalMap({0, 1, 2}, 2, 10, 90);
  ASSERT_EQ(replica->slots().size(), 3u);
  const MapPoint* point = replica->map().point(102);
  ASSERT_NE(point, nullptr);
  EXPECT_EQ(point->depth_record.checks, 3);
  EXPECT_TRUE(point->depth_record.expectsReadingAt(2.0));
}

TEST_F(LocalMap, ACameraThatComesBackThawsNearestFirstWithinTheBudget) {
  replica->updateLocalMap({0}, 2, 10, 90);
  const LocalMapChange change = replica->updateLocalMap({2, 1}, 1, 10, 90);
  EXPECT_EQ(change.thawed, 1);
  EXPECT_EQ(change.left_cold, 1);
  EXPECT_EQ(change.frozen, 1) << "keyframe 0 left the window";
  EXPECT_FALSE(keyframe(2).cold());
  EXPECT_TRUE(keyframe(1).cold());
  ASSERT_EQ(keyframe(2).pyramid.numLevels(), kMaxLevels);
  cv::Mat difference;
  cv::absdiff(keyframe(2).grey(), originals[2], difference);
  EXPECT_LT(cv::mean(difference)[0], 3.0) << "JPEG at quality 90";
  // Slots for the thawed keyframe's point, none for the keyframes now cold.
  ASSERT_EQ(replica->slots().size(), 1u);
  EXPECT_EQ(replica->slots()[0].source, &keyframe(2));
  EXPECT_EQ(replica->slots()[0].patch_level, -1) << "no patch cache yet";
  replica->updateLocalMap({2, 1}, 1, 10, 90);
  EXPECT_FALSE(keyframe(1).cold()) << "the rest of the window follows on the next call";
  EXPECT_EQ(replica->slots().size(), 2u);
}

// With a keyframe store, a cold keyframe's JPEG is on storage, not in memory; thawed, it
// comes back as without one; culled, its entry goes.
TEST_F(LocalMap, AStoreHoldsTheColdKeyframesImages) {
  Expected<std::unique_ptr<KeyframeStore>> store = KeyframeStore::open(::testing::TempDir());
  ASSERT_TRUE(store) << store.error();
  replica->setStore(store->get());
  replica->updateLocalMap({0}, 2, 10, 90);
  for (KeyframeId id : {1, 2}) {
    EXPECT_TRUE(keyframe(id).cold());
    EXPECT_TRUE(keyframe(id).cold_grey.empty()) << "in the store, not in memory";
    EXPECT_TRUE((*store)->has(id, KeyframeStore::Kind::kImage));
  }
  EXPECT_GT((*store)->bytes(), 2000);
  replica->updateLocalMap({2}, 1, 10, 90);
  ASSERT_FALSE(keyframe(2).cold());
  cv::Mat difference;
  cv::absdiff(keyframe(2).grey(), originals[2], difference);
  EXPECT_LT(cv::mean(difference)[0], 3.0) << "JPEG at quality 90";
  const int64_t stored = (*store)->bytes();
  replica->updateLocalMap({0}, 1, 10, 90);
  EXPECT_TRUE(keyframe(2).cold());
  EXPECT_EQ((*store)->bytes(), stored) << "frozen again: the stored JPEG is kept, not made again";
  acknowledgeAll();
  MapUpdate cull;
  cull.version = 2;
  cull.removed_keyframes = {2};
  replica->apply(cull);
  EXPECT_FALSE((*store)->has(2, KeyframeStore::Kind::kImage)) << "a culled keyframe's entry goes";
  EXPECT_TRUE((*store)->has(1, KeyframeStore::Kind::kImage));
  replica->clear();
  EXPECT_EQ((*store)->entries(), 0u);
  EXPECT_EQ((*store)->errors(), 0);
  replica->setStore(nullptr);  // the store goes before the fixture's replica
}

// A keyframe that leaves the wanted list stays hot while the hot set is within the window,
// so one that comes back a frame later is not frozen and thawed again (JPEG each time); over
// the window the oldest goes first.
TEST_F(LocalMap, KeyframesNotWantedStayHotWithinTheWindow) {
  LocalMapChange change = replica->updateLocalMap({0}, 2, 10, 90, 3);
  EXPECT_EQ(change.frozen, 0);
  EXPECT_EQ(replica->hotKeyframes(), 3);
  change = replica->updateLocalMap({2}, 2, 10, 90, 2);
  EXPECT_EQ(change.frozen, 1);
  EXPECT_TRUE(keyframe(0).cold()) << "the oldest not wanted";
  EXPECT_FALSE(keyframe(1).cold());
  EXPECT_FALSE(keyframe(2).cold());
  change = replica->updateLocalMap({0}, 2, 10, 90, 2);
  EXPECT_EQ(change.thawed, 1);
  EXPECT_EQ(change.frozen, 1) << "thawing one over the window freezes one";
  EXPECT_EQ(replica->hotKeyframes(), 2);
  EXPECT_FALSE(keyframe(0).cold());
}

TEST_F(LocalMap, FreezingIsBoundedPerCall) {
  const LocalMapChange change = replica->updateLocalMap({}, 2, 1, 90);
  EXPECT_EQ(change.frozen, 1);
  EXPECT_EQ(replica->hotKeyframes(), 2);
}

// A lost tracker thaws around one relocalisation candidate after another: each call freezes
// at least as many as it thawed, so the hot set does not grow with the candidates tried.
TEST_F(LocalMap, ThawingForOneCandidateAfterAnotherKeepsTheHotSetBounded) {
  replica->updateLocalMap({0}, 0, 10, 90);
  ASSERT_EQ(replica->hotKeyframes(), 1);
  for (int round = 0; round < 3; ++round) {
    for (const std::vector<KeyframeId>& around : {std::vector<KeyframeId>{1, 2}, std::vector<KeyframeId>{0}}) {
      const LocalMapChange change = replica->updateLocalMap(around, 8, 1, 90);
      EXPECT_EQ(change.thawed, static_cast<int>(around.size()));
      EXPECT_EQ(replica->hotKeyframes(), static_cast<int>(around.size()))
          << "with only max_freezes (1) going back the hot set would grow";
      for (KeyframeId id : around) EXPECT_FALSE(keyframe(id).cold());
    }
  }
}

// The mapper culled keyframe 1 (a delta names it): point 101, which it described, comes
// re-described by keyframe 2 and keeps a slot; the keyframe and its measurements go.
TEST_F(LocalMap, AKeyframeCulledByTheMapperLeavesTheReplica) {
  acknowledgeAll();
  replica->addProvisionalPoint(NewPoint{MapPoint(MapPointData{300, Vec3(1, 0, 2), 1, {300, 200}, 0}),
                                           Measurement{300, {300, 200}, 0, 2.0}});  // the mapper never had it
  MapUpdate delta;
  delta.version = 2;
  delta.points.push_back(MapPointData{101, Vec3(1, 0, 2), 2, Eigen::Vector2d(250, 240), 1});
  delta.removed_keyframes = {1};
  EXPECT_TRUE(replica->apply(delta));
  EXPECT_FALSE(replica->map().hasKeyframe(1));
  ASSERT_NE(replica->map().point(101), nullptr);
  EXPECT_EQ(replica->map().point(101)->source_keyframe, 2);
  EXPECT_EQ(replica->map().point(300), nullptr) << "still described by the culled keyframe";
  std::vector<PointId> slots;
  for (const PointSlot& slot : replica->slots()) {
    slots.push_back(slot.point->id);
    EXPECT_NE(slot.source->id, 1);
  }
  std::sort(slots.begin(), slots.end());
  EXPECT_EQ(slots, (std::vector<PointId>{100, 101, 102}));
  // Keyframe 0 and keyframes not acknowledged are never culled: a message naming them is
  // refused for them (a hostile or corrupt one; the mapper never sends it).
  replica->addKeyframe(makeKeyframe(KeyframeData{0, 0, 3, SE3(), originals[0], {}, 5000.0, {}, {}},
                                    KeyframeBuildOptions{}));
  MapUpdate hostile;
  hostile.version = 3;
  hostile.removed_keyframes = {0, 3};
  EXPECT_FALSE(replica->apply(hostile));
  EXPECT_TRUE(replica->map().hasKeyframe(0));
  EXPECT_TRUE(replica->map().hasKeyframe(3));
  // A snapshot lists every keyframe culled so far (the delta naming keyframe 2 was lost); an
  // acknowledged keyframe merely absent from it stays (a mapper that lost its journal).
  MapUpdate snapshot;
  snapshot.version = 5;
  snapshot.is_snapshot = true;
  snapshot.acked_below = 3;
  snapshot.keyframes = {{0, keyframe(0).T_w_c}};
  snapshot.points.push_back(MapPointData{100, Vec3(0, 0, 2), 0, Eigen::Vector2d(320, 240), 0});
  snapshot.removed_keyframes = {1, 2};
  EXPECT_TRUE(replica->apply(snapshot));
  EXPECT_EQ(replica->map().numKeyframes(), 2u) << "keyframes 0 and 3 (not yet acknowledged)";
  EXPECT_EQ(replica->map().numPoints(), 1u);
  EXPECT_EQ(replica->slots().size(), 1u);
  LocalMap::SetUp();
  snapshot.removed_keyframes.clear();
  EXPECT_TRUE(replica->apply(snapshot));
  EXPECT_EQ(replica->map().numKeyframes(), 3u) << "keyframes absent from a snapshot but not culled stay";
}

// The index of the points each keyframe describes, and their bounds, follow every change
// the replica makes to the points (checked against a pass over the whole map): points added,
// re-described from another keyframe, moved far, removed; a keyframe going cold and culled.
TEST_F(LocalMap, TheIndexOfEachKeyframesPointsFollowsTheMap) {
  const auto check = [&](const char* when) {
    std::map<KeyframeId, std::vector<PointId>> expected;
    for (const auto& [id, point] : replica->map().points()) expected[point.source_keyframe].push_back(id);
    for (const auto& [kf, keyframe] : replica->map().keyframes()) {
      std::vector<PointId> indexed = replica->describedBy(kf);
      std::sort(indexed.begin(), indexed.end());
      std::sort(expected[kf].begin(), expected[kf].end());
      EXPECT_EQ(indexed, expected[kf]) << when << ", keyframe " << kf;
      const MapReplica::Bounds bounds = replica->boundsOf(kf);
      if (!indexed.empty()) {
        EXPECT_GE(bounds.radius, 0.0) << when << ", keyframe " << kf;
      }
      for (PointId pid : indexed) {
        EXPECT_LE((replica->map().point(pid)->p_w - bounds.centre).norm(), bounds.radius)
            << when << ", point " << pid << " outside its keyframe's bounds";
      }
    }
  };
  check("set up");
  for (PointId id = 0; id < 20; ++id) {
    replica->addProvisionalPoint(NewPoint{MapPoint(MapPointData{id, Vec3(0.1 * id, -0.5, 1.0 + 0.2 * id), id % 3,
                                                                {300, 200}, 0}),
                                          Measurement{id, {300, 200}, 0, 1.0}});
  }
  check("points added");
  replica->updateLocalMap({0}, 2, 10, 90);
  EXPECT_TRUE(keyframe(1).cold());
  check("keyframes 1 and 2 cold");
  acknowledgeAll();
  MapUpdate delta;
  delta.version = 2;
  delta.points.push_back(MapPointData{4, Vec3(3, 1, 4), 2, Eigen::Vector2d(250, 240), 1});  // re-described by 2
  delta.moved_points.push_back(PointPosition{5, Vec3(-8, 2, 9)});                           // far from the rest
  delta.moved_points.push_back(PointPosition{7, Vec3(0.7, -0.4, 2.5)});
  delta.removed_points = {8, 11};
  ASSERT_TRUE(replica->apply(delta));
  check("a delta applied");
  EXPECT_GT(replica->boundsOf(2).radius, 5.0) << "grown to the far point";
  ASSERT_TRUE(replica->apply(removal(3, {5}, {})));
  check("the far point removed");
  EXPECT_GT(replica->boundsOf(2).radius, 5.0) << "never shrunk while cold";
  replica->updateLocalMap({2}, 2, 10, 90);  // keyframe 2 thawed...
  EXPECT_FALSE(keyframe(2).cold());
  replica->updateLocalMap({0}, 2, 10, 90);  // ...and frozen again: its bounds exact
  EXPECT_TRUE(keyframe(2).cold());
  check("keyframe 2 frozen again");
  EXPECT_LT(replica->boundsOf(2).radius, 3.0) << "exact again without the far point";
  ASSERT_TRUE(replica->apply(removal(4, {}, {1})));
  EXPECT_FALSE(replica->map().hasKeyframe(1));
  EXPECT_TRUE(replica->describedBy(1).empty());
  check("keyframe 1 culled");
}

// A map version's work on cold keyframes' points waits (apply with defer_cold) while what the
// search uses goes in at once, and once done it leaves the replica as a whole apply would:
// a delta (re-described, moved and removed points, a culled keyframe) and then a snapshot.
TEST_F(LocalMap, WorkOnColdKeyframesWaitsAndEndsAsAWholeApply) {
  auto whole = anotherReplica();
  for (MapReplica* r : {replica.get(), whole.get()}) {
    for (PointId id = 0; id < 30; ++id) {
      r->addProvisionalPoint(NewPoint{MapPoint(MapPointData{id, Vec3(0.1 * id, -0.5, 1.0 + 0.1 * id), id % 3,
                                                            {300, 200}, 0}),
                                      Measurement{id, {300, 200}, 0, 1.0}});
    }
    r->updateLocalMap({0}, 2, 10, 90);  // keyframes 1 and 2 cold
    acknowledgeAll(r);
  }
  ASSERT_TRUE(keyframe(1).cold() && keyframe(2).cold() && !keyframe(0).cold());
  MapUpdate delta;
  delta.version = 2;
  delta.keyframes = {{0, SE3(Mat3::Identity(), Vec3(0, 0.5, 0)), 0}, {2, SE3(), 0}};
  delta.points.push_back(MapPointData{4, Vec3(3, 1, 4), 2, Eigen::Vector2d(250, 240), 1});  // 1 -> 2, cold
  delta.points.push_back(MapPointData{7, Vec3(1, 1, 4), 0, Eigen::Vector2d(250, 240), 0});  // 1 -> 0, hot
  delta.moved_points = {{3, Vec3(0.3, 0.1, 2)}, {5, Vec3(0.5, 0.1, 2)}};                   // hot, cold: both at once
  delta.removed_points = {6, 8};                                                              // hot, cold
  delta.removed_keyframes = {1};                                                              // cold
  const auto check_hot = [&](const char* when) {
    EXPECT_EQ(keyframe(0).T_w_c.translation().y(), 0.5) << when;
    EXPECT_EQ(replica->map().point(7)->source_keyframe, 0) << when;
    EXPECT_EQ(replica->map().point(3)->p_w.y(), 0.1) << when;
    EXPECT_EQ(replica->map().point(5)->p_w.y(), 0.1) << when;
    EXPECT_EQ(replica->map().point(6), nullptr) << when;
  };
  ASSERT_TRUE(replica->apply(delta, /*defer_cold=*/true));
  ASSERT_TRUE(whole->apply(delta));
  check_hot("at once");
  EXPECT_TRUE(replica->hasDeferred());
  EXPECT_FALSE(replica->map().hasKeyframe(1)) << "culled at once";
  EXPECT_EQ(replica->map().point(4)->source_keyframe, 2) << "re-described from the culled keyframe: at once";
  EXPECT_EQ(replica->map().point(13), nullptr) << "went with keyframe 1";
  EXPECT_NE(replica->map().point(8), nullptr) << "cold keyframe 2's: waits";
  for (int steps = 0; replica->applyDeferred(1) > 0;) ASSERT_LT(++steps, 100);
  EXPECT_EQ(replica->map().point(8), nullptr);
  check_hot("after");
  const auto same = [&](const char* when) {
    ASSERT_EQ(replica->map().numPoints(), whole->map().numPoints()) << when;
    ASSERT_EQ(replica->map().numKeyframes(), whole->map().numKeyframes()) << when;
    for (const auto& [id, point] : whole->map().points()) {
      const MapPoint* mine = replica->map().point(id);
      ASSERT_NE(mine, nullptr) << when << ", point " << id;
      EXPECT_EQ(mine->p_w, point.p_w) << when << ", point " << id;
      EXPECT_EQ(mine->source_keyframe, point.source_keyframe) << when << ", point " << id;
    }
    for (const auto& [id, kf] : whole->map().keyframes()) {
      std::vector<PointId> a = replica->describedBy(id), b = whole->describedBy(id);
      std::sort(a.begin(), a.end());
      std::sort(b.begin(), b.end());
      EXPECT_EQ(a, b) << when << ", keyframe " << id;
    }
    std::vector<PointId> a, b;
    for (const PointSlot& slot : replica->slots()) a.push_back(slot.point->id);
    for (const PointSlot& slot : whole->slots()) b.push_back(slot.point->id);
    EXPECT_EQ(a, b) << when;
  };
  same("the delta");
  // A snapshot: every point but 9 and 11 (hot keyframe 0's and cold keyframe 2's: culled),
  // each moved. Work left from it is done first by the next version.
  MapUpdate snapshot;
  snapshot.version = 3;
  snapshot.is_snapshot = true;
  snapshot.acked_below = 3;
  for (const auto& [id, kf] : whole->map().keyframes()) snapshot.keyframes.push_back({id, kf->T_w_c, 0});
  for (const auto& [id, point] : whole->map().points()) {
    if (id == 9 || id == 11) continue;
    MapPointData data = point.data();
    data.p_w.z() += 0.25;
    snapshot.points.push_back(data);
  }
  std::sort(snapshot.points.begin(), snapshot.points.end(),
            [](const MapPointData& a, const MapPointData& b) { return a.id < b.id; });
  ASSERT_TRUE(replica->apply(snapshot, /*defer_cold=*/true));
  ASSERT_TRUE(whole->apply(snapshot));
  EXPECT_EQ(replica->map().point(9), nullptr) << "hot: at once";
  EXPECT_NE(replica->map().point(11), nullptr) << "cold: waits";
  EXPECT_NE(replica->map().point(14)->p_w.z(), whole->map().point(14)->p_w.z()) << "cold: waits";
  EXPECT_EQ(replica->map().point(12)->p_w.z(), whole->map().point(12)->p_w.z()) << "hot: at once";
  EXPECT_TRUE(replica->hasDeferred());
  ASSERT_GT(replica->applyDeferred(5), 0u) << "a step of 5 entries leaves some";
  MapUpdate next;
  next.version = 4;
  ASSERT_TRUE(replica->apply(next, /*defer_cold=*/true));
  ASSERT_TRUE(whole->apply(next));
  EXPECT_FALSE(replica->hasDeferred());
  same("the snapshot");
}

// With a store, a cold keyframe's points live on storage (LocalMapOptions::store_points):
// whatever a map version does to them, held back or at once, the map read back is the one a
// replica holding every point in memory has, to the last statistic and depth record, and
// while cold the memory holds none of them.
TEST_F(LocalMap, PointsOnStorageGiveTheSameMapAsPointsInMemory) {
  Expected<std::unique_ptr<KeyframeStore>> store = KeyframeStore::open(::testing::TempDir());
  Expected<std::unique_ptr<KeyframeStore>> direct_store = KeyframeStore::open(::testing::TempDir());
  ASSERT_TRUE(store && direct_store);
  auto memory = anotherReplica();
  auto direct = anotherReplica();  // on storage too, every version applied at once
  replica->setStore(store->get());
  direct->setStore(direct_store->get());
  const std::vector<MapReplica*> on_store = {replica.get(), direct.get()};
  for (MapReplica* r : {replica.get(), direct.get(), memory.get()}) {
    for (KeyframeId kf = 0; kf < 3; ++kf) {
      for (int64_t i = 0; i < 6; ++i) {
        const PointId id = provisionalPointId(kf, i);
        r->addProvisionalPoint(NewPoint{MapPoint(MapPointData{id, Vec3(kf + 0.1 * i, -0.5, 1.0 + 0.1 * i), kf,
                                                              {300.0 + i, 200}, static_cast<int>(i % 2)}),
                                        Measurement{id, {300.0 + i, 200}, 0, 1.0}});
      }
    }
    for (PointSlot& slot : r->slots()) {  // statistics as searches leave them
      slot.point->times_projected = static_cast<int>(slot.point->id % 7) + 3;
      slot.point->times_found = static_cast<int>(slot.point->id % 5);
      slot.point->depth_record.add(DepthVerdict::kAgrees, 1.5);
      slot.point->depth_record.add(DepthVerdict::kSeenThrough, 2.0 + 0.01 * static_cast<double>(slot.point->id % 11));
      slot.point->depth_record.add(DepthVerdict::kMissing, 2.5);
    }
    r->updateLocalMap({0}, 2, 10, 90);  // keyframes 1 and 2 cold
    acknowledgeAll(r);
  }
  ASSERT_TRUE(keyframe(1).cold() && keyframe(2).cold() && !keyframe(0).cold());
  const auto positions = [](const MapReplica& r, KeyframeId id) {
    std::vector<std::array<double, 3>> out;
    r.forEachPosition(id, [&](const Vec3& p) { out.push_back({p.x(), p.y(), p.z()}); });
    std::sort(out.begin(), out.end());
    return out;
  };
  const auto apply = [&](const MapUpdate& update, const char* when) {
    const bool known = memory->apply(update);
    ASSERT_EQ(replica->apply(update, /*defer_cold=*/true), known) << when;
    ASSERT_EQ(direct->apply(update), known) << when;
    for (int steps = 0; replica->applyDeferred(3) > 0;) ASSERT_LT(++steps, 100) << when;
    for (MapReplica* r : on_store) {
      EXPECT_EQ(r->numPoints(), memory->map().numPoints()) << when;
      for (const auto& [id, kf] : r->map().keyframes()) {
        if (!kf->cold()) continue;
        EXPECT_TRUE(r->describedBy(id).empty()) << when << ": keyframe " << id << "'s points are on storage";
        EXPECT_EQ(positions(*r, id), positions(*memory, id)) << when << ", keyframe " << id;
      }
    }
  };
  EXPECT_EQ(replica->storedPoints(), 14u) << "six each and the fixture's one";
  EXPECT_EQ(replica->map().numPoints(), 7u);
  EXPECT_EQ((*store)->entries(KeyframeStore::Kind::kPoints), 2u);

  MapUpdate delta;
  delta.version = 2;
  delta.points.push_back(MapPointData{provisionalPointId(1, 0), Vec3(3, 1, 4), 2, {250, 240}, 1});  // 1 -> 2
  delta.points.push_back(MapPointData{provisionalPointId(1, 1), Vec3(1, 1, 4), 0, {250, 240}, 0});  // 1 -> 0, hot
  delta.points.push_back(MapPointData{mapperPointId(2, 0), Vec3(2, 2, 4), 2, {270, 240}, 0});       // new, cold
  delta.moved_points = {{provisionalPointId(2, 2), Vec3(2.2, 0.1, 2)}, {provisionalPointId(0, 2), Vec3(0.2, 0.1, 2)}};
  delta.removed_points = {provisionalPointId(2, 3), provisionalPointId(0, 3)};
  delta.removed_keyframes = {1};
  apply(delta, "the delta");
  EXPECT_EQ((*store)->entries(KeyframeStore::Kind::kPoints), 1u) << "keyframe 1's went with it";

  MapUpdate moves;  // only points on storage: moved and removed in memory's lists, no read
  moves.version = 3;
  moves.moved_points = {{provisionalPointId(2, 5), Vec3(2.5, 0.3, 2)}, {provisionalPointId(2, 0), Vec3(2, 0.3, 2)}};
  moves.removed_points = {provisionalPointId(2, 2)};
  apply(moves, "the moves");
  MapUpdate taken;  // a point taken from a keyframe on storage to a hot one
  taken.version = 4;
  taken.points.push_back(MapPointData{provisionalPointId(2, 1), Vec3(2, 1, 4), 0, {260, 240}, 0});
  apply(taken, "the point taken");
  EXPECT_EQ(replica->map().point(provisionalPointId(2, 1))->depth_record.checks, 2) << "with its depth record";

  MapUpdate snapshot;  // every point moved but two of keyframe 2 (culled)
  snapshot.version = 5;
  snapshot.is_snapshot = true;
  snapshot.acked_below = 3;
  for (const auto& [id, kf] : memory->map().keyframes()) snapshot.keyframes.push_back({id, kf->T_w_c, 0});
  for (const auto& [id, point] : memory->map().points()) {
    if (id == provisionalPointId(2, 4) || id == mapperPointId(2, 0)) continue;
    MapPointData data = point.data();
    data.p_w.z() += 0.25;
    snapshot.points.push_back(data);
  }
  apply(snapshot, "the snapshot");

  for (MapReplica* r : {replica.get(), direct.get(), memory.get()}) r->updateLocalMap({0, 2}, 2, 10, 90);  // thawed
  EXPECT_EQ(replica->storedPoints(), 0u);
  EXPECT_EQ((*store)->entries(KeyframeStore::Kind::kPoints), 1u) << "kept until it is frozen again";
  replica->updateLocalMap({0}, 2, 10, 90, 1);  // frozen again: written without the points removed meanwhile
  replica->updateLocalMap({0, 2}, 2, 10, 90);
  const size_t holes = (*store)->queued();
  replica->updateLocalMap({0}, 2, 10, 90, 1);  // and again, unsearched
  EXPECT_EQ((*store)->queued(), holes) << "the same bytes are not written again";
  EXPECT_GT(replica->storedPoints(), 0u);
  replica->updateLocalMap({0, 2}, 2, 10, 90);
  for (MapReplica* r : on_store) {
    ASSERT_EQ(r->map().numPoints(), memory->map().numPoints());
    for (const auto& [id, point] : memory->map().points()) {
      const MapPoint* mine = r->map().point(id);
      ASSERT_NE(mine, nullptr) << "point " << id;
      EXPECT_EQ(mine->p_w, point.p_w) << "point " << id;
      EXPECT_EQ(mine->source_keyframe, point.source_keyframe) << "point " << id;
      EXPECT_EQ(mine->source_level, point.source_level) << "point " << id;
      EXPECT_EQ(mine->source_uv, point.source_uv) << "point " << id;
      EXPECT_EQ(mine->times_projected, point.times_projected) << "point " << id;
      EXPECT_EQ(mine->times_found, point.times_found) << "point " << id;
      EXPECT_EQ(mine->depth_record.checks, point.depth_record.checks) << "point " << id;
      EXPECT_EQ(mine->depth_record.seen_through, point.depth_record.seen_through) << "point " << id;
      EXPECT_EQ(mine->depth_record.missing, point.depth_record.missing) << "point " << id;
      EXPECT_EQ(mine->depth_record.read_max_m, point.depth_record.read_max_m) << "point " << id;
    }
    for (const auto& [id, kf] : memory->map().keyframes()) {
      std::vector<PointId> a = r->describedBy(id), b = memory->describedBy(id);
      std::sort(a.begin(), a.end());
      std::sort(b.begin(), b.end());
      EXPECT_EQ(a, b) << "keyframe " << id;
    }
    std::vector<PointId> a, b;
    for (const PointSlot& slot : r->slots()) a.push_back(slot.point->id);
    for (const PointSlot& slot : memory->slots()) b.push_back(slot.point->id);
    EXPECT_EQ(a, b) << "the search order";
    EXPECT_EQ(r->pointsLost(), 0);
  }
  EXPECT_EQ((*store)->errors() + (*direct_store)->errors(), 0);
  replica->setStore(nullptr);  // the stores go before the fixture's replicas
  direct->setStore(nullptr);
  direct.reset();
}

// Freezing or culling a keyframe removes its points' slots in slot order, as a scan of the
// slots would, even where the index lists them in another order (a point re-described by
// the keyframe comes last in its list): a removal moves the last slot into the gap, so the
// order of removal decides the slots' order, and with it the tracker's search order.
class SlotOrder : public LocalMap {
 protected:
  // Points 0-19 described by keyframe id % 3, then point 'moved' re-described by keyframe
  // 'to': last in that keyframe's index.
  void SetUpPoints(PointId moved, KeyframeId to) {
    for (PointId id = 0; id < 20; ++id) {
      replica->addProvisionalPoint(NewPoint{MapPoint(MapPointData{id, Vec3(0.1 * id, -0.5, 1.0 + 0.2 * id), id % 3,
                                                                  {300, 200}, 0}),
                                            Measurement{id, {300, 200}, 0, 1.0}});
    }
    acknowledgeAll();
    MapUpdate delta;
    delta.version = 2;
    delta.points.push_back(MapPointData{moved, Vec3(0.4, -0.5, 1.8), to, Eigen::Vector2d(250, 240), 0});
    ASSERT_TRUE(replica->apply(delta));
    ASSERT_EQ(replica->describedBy(to).back(), moved) << "the re-described point is last in the index";
  }
  // The order a scan gives: the keyframe's slots found in slot order, each removal moving
  // the last slot into its place.
  std::vector<PointId> scanOrderWithout(KeyframeId kf) const {
    std::vector<PointId> expected;
    for (const PointSlot& slot : replica->slots()) expected.push_back(slot.point->id);
    std::vector<PointId> described;
    for (const PointSlot& slot : replica->slots()) {
      if (slot.point->source_keyframe == kf) described.push_back(slot.point->id);
    }
    EXPECT_EQ(described.size(), 9u);  // 101, 1, 4, ..., 19 and the re-described 3
    for (PointId id : described) {
      const auto it = std::find(expected.begin(), expected.end(), id);
      *it = expected.back();
      expected.pop_back();
    }
    return expected;
  }
  std::vector<PointId> slotOrder() const {
    std::vector<PointId> order;
    for (const PointSlot& slot : replica->slots()) order.push_back(slot.point->id);
    return order;
  }
};

TEST_F(SlotOrder, FreezingKeepsTheSlotsOrderOfAScan) {
  SetUpPoints(3, 1);  // 0 -> 1: keyframe 1 describes 101, 1, 4, 7, 10, 13, 16, 19, 3
  const std::vector<PointId> expected = scanOrderWithout(1);
  replica->updateLocalMap({0, 2}, 2, 10, 90);
  ASSERT_TRUE(keyframe(1).cold());
  EXPECT_EQ(slotOrder(), expected);
}

// The mapper culling a keyframe (its points not re-described elsewhere go with it) is found
// from the index, not a pass over the map, in the same order.
TEST_F(SlotOrder, CullingKeepsTheSlotsOrderOfAScan) {
  SetUpPoints(3, 1);
  const std::vector<PointId> expected = scanOrderWithout(1);
  ASSERT_TRUE(replica->apply(removal(3, {}, {1})));
  ASSERT_FALSE(replica->map().hasKeyframe(1));
  EXPECT_EQ(slotOrder(), expected);
}

}  // namespace
}  // namespace rgbdslam
