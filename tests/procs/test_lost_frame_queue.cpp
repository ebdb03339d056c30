#include "common/lost_frame_queue.h"

#include <gtest/gtest.h>

#include <vector>

namespace rgbdslam {
namespace {

RgbdFrame passedFrame(int64_t seq) {
  RgbdFrame frame;
  frame.seq = seq;
  frame.utime = 1000000 + seq * 33333;
  frame.depth_scale = 1000.0;
  frame.depth = cv::Mat(48, 64, CV_16UC1, cv::Scalar::all(static_cast<double>(seq + 1)));
  frame.colour = cv::Mat(48, 64, CV_8UC3, cv::Scalar::all(0));
  return frame;
}

std::vector<int64_t> keptSeqs(const LostFrameQueue& queue) {
  std::vector<int64_t> seqs;
  for (size_t i = 0; i < queue.size(); ++i) seqs.push_back(queue.frame(i).seq);
  return seqs;
}

// At most its capacity, evenly spaced over the frames offered, oldest first: every frame,
// then every 2nd, every 4th. Each kept frame is a copy of the depth (not the colour), with
// its scale and time.
TEST(LostFrameQueue, KeepsAtMostItsCapacityEvenlySpaced) {
  LostFrameQueue queue(3);
  std::vector<std::vector<int64_t>> after;  // the frames kept after each offer
  for (int64_t seq = 0; seq < 9; ++seq) {
    queue.offer(passedFrame(seq));
    after.push_back(keptSeqs(queue));
  }
  EXPECT_EQ(after[2], (std::vector<int64_t>{0, 1, 2}));
  EXPECT_EQ(after[3], (std::vector<int64_t>{0, 2}));
  EXPECT_EQ(after[4], (std::vector<int64_t>{0, 2, 4}));
  EXPECT_EQ(after[5], (std::vector<int64_t>{0, 2, 4}));
  EXPECT_EQ(after[6], (std::vector<int64_t>{0, 4}));
  EXPECT_EQ(after[8], (std::vector<int64_t>{0, 4, 8}));
  EXPECT_EQ(queue.offered(), 9);
  for (size_t i = 0; i < queue.size(); ++i) {
    const RgbdFrame& kept = queue.frame(i);
    const RgbdFrame original = passedFrame(kept.seq);
    EXPECT_EQ(kept.utime, original.utime);
    EXPECT_EQ(kept.depth_scale, original.depth_scale);
    EXPECT_EQ(cv::norm(kept.depth, original.depth, cv::NORM_INF), 0.0) << "frame " << kept.seq;
    EXPECT_TRUE(kept.colour.empty());
  }
}

// Cleared, it starts over with every frame, in the buffers it had (no new allocation for
// frames of the same size); a frame without depth is ignored; capacity 0 keeps nothing.
TEST(LostFrameQueue, StartsOverWhenClearedAndReusesItsBuffers) {
  LostFrameQueue queue(2);
  queue.offer(passedFrame(0));
  queue.offer(passedFrame(1));
  const uint16_t* buffer = queue.frame(0).depth.ptr<uint16_t>();
  queue.offer(passedFrame(2));  // full: every 2nd; frame 2 kept
  EXPECT_EQ(keptSeqs(queue), (std::vector<int64_t>{0, 2}));
  queue.clear();
  EXPECT_EQ(queue.size(), 0u);
  EXPECT_EQ(queue.offered(), 0);
  queue.offer(passedFrame(10));
  queue.offer(passedFrame(11));
  EXPECT_EQ(keptSeqs(queue), (std::vector<int64_t>{10, 11}));
  EXPECT_TRUE(queue.frame(0).depth.ptr<uint16_t>() == buffer || queue.frame(1).depth.ptr<uint16_t>() == buffer)
      << "a buffer of the first round is reused";
  EXPECT_EQ(queue.frame(1).depth.at<uint16_t>(0, 0), 12);

  // A frame without 16-bit depth has nothing to follow: not offered, not counted.
  RgbdFrame no_depth = passedFrame(12), float_depth = passedFrame(13);
  no_depth.depth = cv::Mat();
  float_depth.depth.convertTo(float_depth.depth, CV_32F);
  queue.offer(no_depth);
  queue.offer(float_depth);
  EXPECT_EQ(queue.offered(), 2);
  EXPECT_EQ(keptSeqs(queue), (std::vector<int64_t>{10, 11}));

  LostFrameQueue none(0);
  none.offer(passedFrame(0));
  EXPECT_EQ(none.size(), 0u);
  EXPECT_EQ(none.offered(), 1);
}

}  // namespace
}  // namespace rgbdslam
