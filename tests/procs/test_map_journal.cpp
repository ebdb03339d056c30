#include "common/map_journal.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>

#include "test_support.h"

namespace rgbdslam {
namespace {

off_t fileSize(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 ? st.st_size : -1;
}

TEST(MapJournal, ReloadsKeyframesAndTheLastVersion) {
  test::TempDir dir;
  MapJournal::Contents contents;
  {
    auto journal = MapJournal::open(dir.path(), &contents);
    ASSERT_TRUE(journal) << journal.error();
    EXPECT_TRUE(contents.keyframes.empty());
    EXPECT_EQ(contents.last_version, 0);
    const std::string a = "first keyframe", b = "second";
    ASSERT_TRUE(journal->appendKeyframe(a.data(), a.size()));
    ASSERT_TRUE(journal->appendVersion(7));
    ASSERT_TRUE(journal->appendKeyframe(b.data(), b.size()));
    ASSERT_TRUE(journal->appendCulled({4, 6}));
    ASSERT_TRUE(journal->appendVersion(9));
    ASSERT_TRUE(journal->appendCulled({8}));
  }
  auto again = MapJournal::open(dir.path(), &contents);
  ASSERT_TRUE(again) << again.error();
  ASSERT_EQ(contents.keyframes.size(), 2u);
  EXPECT_EQ(std::string(contents.keyframes[1].begin(), contents.keyframes[1].end()), "second");
  EXPECT_EQ(contents.last_version, 9);
  EXPECT_EQ(contents.culled, (std::vector<KeyframeId>{4, 6, 8}));
  EXPECT_TRUE(contents.warning.empty());
}

TEST(MapJournal, DropsATornRecordAndAppendsAfterTheLastGoodOne) {
  test::TempDir dir;
  MapJournal::Contents contents;
  {
    auto journal = MapJournal::open(dir.path(), &contents);
    ASSERT_TRUE(journal);
    const std::string a = "kept";
    ASSERT_TRUE(journal->appendKeyframe(a.data(), a.size()));
  }
  const std::string path = dir.file("map.journal");
  const off_t good = fileSize(path);
  {
    std::ofstream out(path, std::ios::binary | std::ios::app);
    out.write("MJ1\x01\x40\x00\x00\x00", 8);  // a header claiming 64 bytes, then the end
  }
  {
    auto journal = MapJournal::open(dir.path(), &contents);
    ASSERT_TRUE(journal) << journal.error();
    EXPECT_EQ(contents.keyframes.size(), 1u);
    EXPECT_NE(contents.warning.find("dropped 8 bytes"), std::string::npos) << contents.warning;
    EXPECT_EQ(fileSize(path), good);
    const std::string b = "after";
    ASSERT_TRUE(journal->appendKeyframe(b.data(), b.size()));
  }
  auto last = MapJournal::open(dir.path(), &contents);
  ASSERT_TRUE(last);
  ASSERT_EQ(contents.keyframes.size(), 2u);
  EXPECT_TRUE(contents.warning.empty());
}

TEST(MapJournal, ACorruptPayloadIsDetectedByItsChecksum) {
  test::TempDir dir;
  MapJournal::Contents contents;
  {
    auto journal = MapJournal::open(dir.path(), &contents);
    ASSERT_TRUE(journal);
    const std::string a = "abcdef";
    ASSERT_TRUE(journal->appendKeyframe(a.data(), a.size()));
  }
  {
    std::fstream f(dir.file("map.journal"), std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(14);
    f.put('X');  // inside the payload
  }
  auto journal = MapJournal::open(dir.path(), &contents);
  ASSERT_TRUE(journal);
  EXPECT_TRUE(contents.keyframes.empty());
  EXPECT_FALSE(contents.warning.empty());
}

TEST(MapJournal, AnUnwritableFolderIsAnError) {
  MapJournal::Contents contents;
  auto journal = MapJournal::open("/proc/no-such-folder/state", &contents);
  ASSERT_FALSE(journal);
  EXPECT_NE(journal.error().find("/proc/no-such-folder/state"), std::string::npos) << journal.error();
}

}  // namespace
}  // namespace rgbdslam

namespace rgbdslam {
namespace {

// Issue 13: a map.journal that is a directory crashed the mapper (an uncaught exception
// from reading it as a stream).
TEST(MapJournal, AJournalThatIsADirectoryIsAnError) {
  test::TempDir dir;
  ASSERT_EQ(::mkdir(dir.file("map.journal").c_str(), 0755), 0);
  MapJournal::Contents contents;
  auto journal = MapJournal::open(dir.path(), &contents);
  ASSERT_FALSE(journal);
  EXPECT_NE(journal.error().find(dir.file("map.journal")), std::string::npos) << journal.error();
  EXPECT_NE(journal.error().find("not a regular file"), std::string::npos) << journal.error();
}

}  // namespace
}  // namespace rgbdslam
