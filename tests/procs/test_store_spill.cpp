// rgbd-tracker's outbox with its spill on storage (common/store_spill.h): a long link outage
// keeps at most sync.unacked_in_memory keyframes in memory, and every keyframe still goes
// out, byte for byte and in order, once the link is back.
#include "common/store_spill.h"

#include <gtest/gtest.h>

#include "rgbdslam/sync/keyframe_outbox.h"
#include "test_support.h"

namespace rgbdslam {
namespace {

constexpr int64_t kS = 1000000;  // one second [us]

std::vector<uint8_t> messageOf(KeyframeId id) {
  return std::vector<uint8_t>(30000 + static_cast<size_t>(id), static_cast<uint8_t>(id * 7 + 1));
}

TEST(StoreSpill, AnOutageKeepsFewKeyframesInMemoryAndLosesNone) {
  test::TempDir dir;
  auto store = KeyframeStore::open(dir.path());
  ASSERT_TRUE(store) << store.error();
  StoreSpill spill(store->get());
  KeyframeOutboxOptions options;  // re-send the oldest 2; 64 acknowledged retained
  options.in_memory = 4;
  KeyframeOutbox<std::vector<uint8_t>> outbox(options);
  outbox.setSpill(&spill);
  // The outage: a keyframe a second for 100 s, none acknowledged.
  for (KeyframeId id = 0; id < 100; ++id) {
    outbox.sent(id, messageOf(id), id * kS);
    (void)outbox.resendsDue(id * kS);
    ASSERT_LE(outbox.inMemory(), 4u) << "after keyframe " << id;
  }
  EXPECT_EQ(outbox.size(), 100u);
  EXPECT_EQ(outbox.spilled(), 96u);
  EXPECT_EQ((*store)->entries(KeyframeStore::Kind::kMessage), 96u);
  // The link is back: each re-send is acknowledged, oldest first, and every message is the
  // one sent.
  int64_t t = 200 * kS;
  for (KeyframeId next = 0; next < 100; t += 10 * kS) {
    const std::vector<const std::vector<uint8_t>*> due = outbox.resendsDue(t);
    ASSERT_FALSE(due.empty()) << "keyframe " << next << " is not re-sent";
    for (const std::vector<uint8_t>* message : due) {
      ASSERT_EQ(*message, messageOf(next)) << "keyframe " << next;
      ++next;
    }
    (void)outbox.acknowledgeBelow(next, t);
    ASSERT_LE(outbox.inMemory(), 4u);
  }
  EXPECT_TRUE(outbox.empty());
  EXPECT_EQ(outbox.spillErrors(), 0);
  EXPECT_EQ((*store)->entries(), 0u) << "nothing left on storage";
  // A mapper that lost the newest acknowledged: they are sent again from memory (retained).
  EXPECT_EQ(outbox.resendFrom(90, t), 10);
  const auto again = outbox.resendsDue(t);
  ASSERT_EQ(again.size(), 2u);
  EXPECT_EQ(*again[0], messageOf(90));
}

// The mapper got the first send of keyframes that were then spilled: acknowledged straight
// from storage, the newest 'retained' read back for a mapper that may lose them, the rest
// dropped; nothing is left on storage, also when the outbox goes.
TEST(StoreSpill, SpilledKeyframesAcknowledgedDirectlyLeaveNothingOnStorage) {
  test::TempDir dir;
  auto store = KeyframeStore::open(dir.path());
  ASSERT_TRUE(store) << store.error();
  StoreSpill spill(store->get());
  for (int retained : {3, 0}) {
    KeyframeOutboxOptions options;
    options.in_memory = 2;
    options.retained = retained;
    {
      KeyframeOutbox<std::vector<uint8_t>> outbox(options);
      outbox.setSpill(&spill);
      for (KeyframeId id = 0; id < 10; ++id) outbox.sent(id, messageOf(id), 0);
      outbox.sent(9, messageOf(9), 0);  // the same keyframe again: replaced, not doubled
      ASSERT_EQ(outbox.spilled(), 8u);
      ASSERT_EQ((*store)->entries(), 8u);
      (void)outbox.acknowledgeBelow(8, kS);
      EXPECT_EQ((*store)->entries(), 2u) << "keyframes 8 and 9 still wait there";
      EXPECT_EQ(outbox.inMemory(), 0u);
      EXPECT_EQ(outbox.spillErrors(), 0);
      EXPECT_EQ(outbox.resendFrom(5, kS), retained) << "retained " << retained;
      if (retained > 0) {
        const auto due = outbox.resendsDue(kS);
        ASSERT_EQ(due.size(), 2u);
        EXPECT_EQ(*due[0], messageOf(5));
        EXPECT_EQ(*due[1], messageOf(6));
      }
    }
    EXPECT_EQ((*store)->entries(), 0u) << "the outbox took its spilled keyframes with it (retained " << retained << ")";
  }
}

// Storage that returns other bytes loses that keyframe (counted), not the others.
TEST(StoreSpill, AKeyframeTheStorageCannotGiveBackIsCountedAndSkipped) {
  test::TempDir dir;
  auto store = KeyframeStore::open(dir.path());
  ASSERT_TRUE(store) << store.error();
  StoreSpill spill(store->get());
  KeyframeOutboxOptions options;
  options.in_memory = 2;
  KeyframeOutbox<std::vector<uint8_t>> outbox(options);
  outbox.setSpill(&spill);
  for (KeyframeId id = 0; id < 5; ++id) outbox.sent(id, messageOf(id), 0);
  ASSERT_EQ(outbox.spilled(), 3u);  // keyframes 2, 3, 4
  (*store)->remove(2, KeyframeStore::Kind::kMessage);  // as after a failed read
  (void)outbox.acknowledgeBelow(2, kS);
  const auto due = outbox.resendsDue(2 * kS);
  ASSERT_EQ(due.size(), 2u);
  EXPECT_EQ(*due[0], messageOf(3));
  EXPECT_EQ(*due[1], messageOf(4));
  EXPECT_EQ(outbox.spillErrors(), 1);
  EXPECT_EQ(outbox.size(), 2u);
}

}  // namespace
}  // namespace rgbdslam
