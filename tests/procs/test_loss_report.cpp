#include "common/loss_report.h"

#include <gtest/gtest.h>

namespace rgbdslam {
namespace {

TrackResult result(TrackResult::Status status, int64_t seq) {
  TrackResult r;
  r.status = status;
  r.pose.seq = seq;
  r.pose.points_tracked = status == TrackResult::Status::kLost ? 3 : 200;
  if (status == TrackResult::Status::kLost) r.lost_reason = "the points found do not fix the pose";
  return r;
}

// One line when tracking is lost, none while it stays lost, one when it comes back, and the
// episode counts; bad frames in between change nothing.
TEST(LossReport, OneLinePerTransition) {
  using S = TrackResult::Status;
  LossReport report;
  EXPECT_EQ(report.update(result(S::kInitialised, 0)), "");
  EXPECT_EQ(report.update(result(S::kTracked, 1)), "");
  const std::string lost = report.update(result(S::kLost, 2));
  EXPECT_NE(lost.find("frame 2: tracking lost (the points found do not fix the pose; 3 points found"), std::string::npos) << lost;
  EXPECT_TRUE(report.lost());
  EXPECT_EQ(report.lostSinceSeq(), 2);
  EXPECT_EQ(report.update(result(S::kLost, 3)), "");
  EXPECT_EQ(report.update(result(S::kBadFrame, 4)), "");
  EXPECT_EQ(report.update(result(S::kLost, 5)), "");
  const std::string back = report.update(result(S::kRelocalised, 6));
  EXPECT_NE(back.find("frame 6: relocalised after 3 lost frames (lost at frame 2"), std::string::npos)
      << back;
  EXPECT_FALSE(report.lost());
  EXPECT_EQ(report.update(result(S::kLost, 9)).empty(), false);
  EXPECT_EQ(report.episodes(), 2);
  EXPECT_EQ(report.relocalisations(), 1);
  EXPECT_TRUE(report.lost());
  EXPECT_EQ(report.lostSinceSeq(), 9);
  EXPECT_EQ(report.update(result(S::kLost, 10)), "");
  TrackResult part = result(S::kTracked, 12);  // lost where nothing relocalises: a new part
  part.new_part = true;
  const std::string started = report.update(part);
  EXPECT_NE(started.find("frame 12: a new part of the map started after 2 lost frames (lost at frame 9"), std::string::npos)
      << started;
  EXPECT_NE(started.find("where the camera coasted to"), std::string::npos) << started;
  EXPECT_FALSE(report.lost());
  EXPECT_EQ(report.update(result(S::kTracked, 13)), "");
  // A part started where depth followed the camera says so.
  EXPECT_EQ(report.update(result(S::kLost, 14)).empty(), false);
  TrackResult reckoned = result(S::kTracked, 20);
  reckoned.new_part = reckoned.part_start_reckoned = true;
  const std::string followed = report.update(reckoned);
  EXPECT_NE(followed.find("frame 20: a new part of the map started after"), std::string::npos) << followed;
  EXPECT_NE(followed.find("where depth followed the camera"), std::string::npos) << followed;
}

}  // namespace
}  // namespace rgbdslam
