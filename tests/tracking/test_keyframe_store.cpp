// The tracker's store of cold keyframes (keyframe_store.h): what goes in comes back, a
// removed or replaced entry gives its bytes back, a directory it cannot use is a clear error.
#include "rgbdslam/tracking/keyframe_store.h"

#include <gtest/gtest.h>

#include <numeric>

namespace rgbdslam {
namespace {

std::vector<uint8_t> bytesOf(size_t size, uint8_t first) {
  std::vector<uint8_t> bytes(size);
  std::iota(bytes.begin(), bytes.end(), first);
  return bytes;
}

TEST(KeyframeStore, GivesBackWhatWasPutUntilItIsRemoved) {
  Expected<std::unique_ptr<KeyframeStore>> opened = KeyframeStore::open(::testing::TempDir());
  ASSERT_TRUE(opened) << opened.error();
  KeyframeStore& store = **opened;
  const std::vector<uint8_t> image = bytesOf(50000, 1), extras = bytesOf(64000, 7);
  ASSERT_TRUE(store.put(3, KeyframeStore::Kind::kImage, image));
  ASSERT_TRUE(store.put(3, KeyframeStore::Kind::kExtras, extras));
  ASSERT_TRUE(store.put(4, KeyframeStore::Kind::kImage, {}));
  EXPECT_EQ(store.entries(), 3u);
  EXPECT_EQ(store.bytes(), 114000);
  EXPECT_GE(store.diskBytes(), 114000) << "the file's blocks";
  EXPECT_EQ(store.entries(KeyframeStore::Kind::kImage), 2u);
  EXPECT_EQ(store.entries(KeyframeStore::Kind::kExtras), 1u);
  EXPECT_TRUE(store.has(3, KeyframeStore::Kind::kImage));
  EXPECT_FALSE(store.has(4, KeyframeStore::Kind::kExtras));
  Expected<std::vector<uint8_t>> back = store.get(3, KeyframeStore::Kind::kImage);
  ASSERT_TRUE(back) << back.error();
  EXPECT_EQ(*back, image);
  back = store.get(3, KeyframeStore::Kind::kExtras);
  ASSERT_TRUE(back) << back.error();
  EXPECT_EQ(*back, extras);
  back = store.get(4, KeyframeStore::Kind::kImage);
  ASSERT_TRUE(back) << back.error();
  EXPECT_TRUE(back->empty());
  // Replaced: the new bytes, and the old ones no longer counted.
  ASSERT_TRUE(store.put(3, KeyframeStore::Kind::kImage, bytesOf(100, 9)));
  EXPECT_EQ(*store.get(3, KeyframeStore::Kind::kImage), bytesOf(100, 9));
  EXPECT_EQ(store.bytes(), 64100);
  store.remove(3);
  EXPECT_EQ(store.entries(), 1u);
  EXPECT_EQ(store.entries(KeyframeStore::Kind::kExtras), 0u);
  EXPECT_EQ(store.bytes(), 0);
  back = store.get(3, KeyframeStore::Kind::kExtras);
  ASSERT_FALSE(back);
  EXPECT_NE(back.error().find("keyframe 3 extras: not stored"), std::string::npos) << back.error();
  store.clear();
  EXPECT_EQ(store.entries(), 0u);
  ASSERT_TRUE(store.put(5, KeyframeStore::Kind::kImage, image)) << "usable after clear()";
  EXPECT_EQ(*store.get(5, KeyframeStore::Kind::kImage), image);
  EXPECT_EQ(store.errors(), 0);
}

// A replaced entry's bytes can be given back later (release_later, as the tracker's points of
// a cold keyframe are replaced between frames): the new bytes at once, the hole queued.
TEST(KeyframeStore, AReplacedEntrysBytesCanGoBackLater) {
  Expected<std::unique_ptr<KeyframeStore>> opened = KeyframeStore::open(::testing::TempDir());
  ASSERT_TRUE(opened) << opened.error();
  KeyframeStore& store = **opened;
  ASSERT_TRUE(store.put(2, KeyframeStore::Kind::kPoints, bytesOf(40000, 1), /*release_later=*/true));
  EXPECT_EQ(store.queued(), 0u) << "nothing replaced";
  ASSERT_TRUE(store.put(2, KeyframeStore::Kind::kPoints, bytesOf(30000, 5), /*release_later=*/true));
  EXPECT_EQ(store.queued(), 1u);
  EXPECT_EQ(store.entries(KeyframeStore::Kind::kPoints), 1u);
  EXPECT_EQ(store.bytes(), 30000);
  EXPECT_EQ(*store.get(2, KeyframeStore::Kind::kPoints), bytesOf(30000, 5));
  EXPECT_EQ(store.releaseQueued(10), 0u);
  EXPECT_EQ(store.queued(), 0u);
  EXPECT_EQ(KeyframeStore::checksum(bytesOf(30000, 5)), KeyframeStore::checksum(*store.get(2, KeyframeStore::Kind::kPoints)));
  EXPECT_NE(KeyframeStore::checksum(bytesOf(30000, 5)), KeyframeStore::checksum(bytesOf(30000, 6)));
  EXPECT_FALSE(store.full());
  EXPECT_EQ(store.errors(), 0);
}

TEST(KeyframeStore, ADirectoryItCannotUseIsAClearError) {
  for (const std::string& directory : {std::string("/nonexistent/rgbd-slam-test"), std::string("/proc/self/status")}) {
    const Expected<std::unique_ptr<KeyframeStore>> opened = KeyframeStore::open(directory);
    ASSERT_FALSE(opened) << directory;
    EXPECT_NE(opened.error().find(directory), std::string::npos) << opened.error();
  }
  EXPECT_FALSE(KeyframeStore::open(""));
}

}  // namespace
}  // namespace rgbdslam
