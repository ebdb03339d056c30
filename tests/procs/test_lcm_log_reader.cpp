// The LCM log reader checks every length itself (issue 13: an event length of 0x7fffffff
// made liblcm's reader write through NULL; garbage, empty and truncated logs gave exit 0
// with no frames).
#include "common/lcm_log_reader.h"

#include <gtest/gtest.h>

#include <fstream>

#include "common/lcm_log_source.h"
#include "sample_messages.h"
#include "test_support.h"

namespace rgbdslam {
namespace {

using test::appendLogEvent;

std::vector<uint8_t> frameLog(int frames) {
  std::vector<uint8_t> log;
  for (int i = 0; i < frames; ++i) {
    appendLogEvent(log, 2 * i, "OTHER", {1, 2, 3});
    appendLogEvent(log, 2 * i + 1, "RGBD_FRAME", test::encode(toLcm(test::sampleFrame(), FrameEncoding{})));
  }
  return log;
}

// Reads the whole log through the frame source; returns the frames and the final status.
std::pair<int, FrameResult> drain(LcmLogSource& source) {
  int frames = 0;
  for (;;) {
    FrameResult result = source.next();
    if (result.status == FrameResult::Status::kFrame) ++frames;
    if (result.status == FrameResult::Status::kEnd || result.status == FrameResult::Status::kFailed) return {frames, result};
  }
}

TEST(LcmLogReader, ReadsEveryEventOfAGoodLog) {
  const auto log = frameLog(3);
  auto reader = LcmLogReader::fromBytes(log.data(), log.size(), "good.lcm");
  ASSERT_TRUE(reader) << reader.error();
  int events = 0;
  for (auto event = reader->next(); event && *event; event = reader->next()) ++events;
  EXPECT_EQ(events, 6);
  auto source = LcmLogSource::fromBytes(log.data(), log.size(), "RGBD_FRAME");
  ASSERT_TRUE(source) << source.error();
  auto [frames, end] = drain(**source);
  EXPECT_EQ(frames, 3);
  EXPECT_EQ(end.status, FrameResult::Status::kEnd);
}

TEST(LcmLogReader, HugeEventLengthIsAnErrorNotACrash) {
  std::vector<uint8_t> log;
  appendLogEvent(log, 0, "RGBD_FRAME", {1, 2, 3, 4}, 0x7fffffff);
  auto reader = LcmLogReader::fromBytes(log.data(), log.size(), "huge.lcm");
  ASSERT_TRUE(reader) << reader.error();
  auto event = reader->next();
  ASSERT_FALSE(event);
  EXPECT_NE(event.error().find("2147483647 data bytes"), std::string::npos) << event.error();
  EXPECT_NE(event.error().find("huge.lcm"), std::string::npos) << event.error();
}

TEST(LcmLogReader, GarbageAndEmptyFilesAreRefusedAtOpen) {
  test::TempDir dir;
  std::ofstream(dir.file("empty.lcm"));
  auto empty = LcmLogSource::open(dir.file("empty.lcm"), "RGBD_FRAME");
  ASSERT_FALSE(empty);
  EXPECT_NE(empty.error().find("empty"), std::string::npos) << empty.error();
  std::ofstream(dir.file("garbage.lcm")) << "this is not an LCM log at all\n";
  auto garbage = LcmLogSource::open(dir.file("garbage.lcm"), "RGBD_FRAME");
  ASSERT_FALSE(garbage);
  EXPECT_NE(garbage.error().find("not an LCM log"), std::string::npos) << garbage.error();
  EXPECT_FALSE(LcmLogSource::open(dir.path(), "RGBD_FRAME"));  // a directory
}

TEST(LcmLogReader, TruncatedLogFailsAfterTheWholeEvents) {
  auto log = frameLog(2);
  log.resize(log.size() - 100);  // the last frame's data cut off
  auto source = LcmLogSource::fromBytes(log.data(), log.size(), "RGBD_FRAME");
  ASSERT_TRUE(source) << source.error();
  auto [frames, end] = drain(**source);
  EXPECT_EQ(frames, 1);
  ASSERT_EQ(end.status, FrameResult::Status::kFailed);
  EXPECT_NE(end.error.find("claims"), std::string::npos) << end.error;
  log.resize(30);  // inside the first header
  source = LcmLogSource::fromBytes(log.data(), log.size(), "RGBD_FRAME");
  ASSERT_TRUE(source);
  EXPECT_EQ(drain(**source).second.status, FrameResult::Status::kFailed);
}

TEST(LcmLogReader, ALogWithoutFramesOnTheChannelFails) {
  const auto log = frameLog(2);
  auto source = LcmLogSource::fromBytes(log.data(), log.size(), "CAMERA");
  ASSERT_TRUE(source) << source.error();
  auto [frames, end] = drain(**source);
  EXPECT_EQ(frames, 0);
  ASSERT_EQ(end.status, FrameResult::Status::kFailed);
  EXPECT_NE(end.error.find("no event on channel CAMERA"), std::string::npos) << end.error;
  EXPECT_NE(end.error.find("OTHER, RGBD_FRAME"), std::string::npos) << end.error;
}

TEST(LcmLogReader, BadSyncWordAndChannelLengthAreErrors) {
  auto log = frameLog(1);  // two good events, then garbage
  log.insert(log.end(), {0xDE, 0xAD, 0xBE, 0xEF});
  log.resize(log.size() + 24, 0);
  auto reader = LcmLogReader::fromBytes(log.data(), log.size(), "bad.lcm");
  ASSERT_TRUE(reader);
  reader->next();
  reader->next();
  auto event = reader->next();
  ASSERT_FALSE(event);
  EXPECT_NE(event.error().find("bad sync word"), std::string::npos) << event.error();
  std::vector<uint8_t> long_channel;
  appendLogEvent(long_channel, 0, std::string(300, 'C'), {});
  reader = LcmLogReader::fromBytes(long_channel.data(), long_channel.size(), "c.lcm");
  ASSERT_TRUE(reader);
  event = reader->next();
  ASSERT_FALSE(event);
  EXPECT_NE(event.error().find("channel length of 300"), std::string::npos) << event.error();
}

}  // namespace
}  // namespace rgbdslam
