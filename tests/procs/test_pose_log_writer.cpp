// pose-logger's writer on its own: whole lines whatever the numbers, no NaN or inf in the
// files, and one map's poses (issue 13: a pose at 1e200 was cut at 256 bytes without a
// newline and glued to the next; two trackers on one bus were merged).
#include "pose-logger/pose_log_writer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <fstream>
#include <sstream>

#include "sample_messages.h"
#include "test_support.h"

namespace rgbdslam {
namespace {

std::vector<std::string> lines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> out;
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

std::string text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream all;
  all << in.rdbuf();
  return all.str();
}

TEST(PoseLogWriter, HugeValuesGiveWholeLines) {
  test::TempDir dir;
  auto writer = PoseLogWriter::open(dir.file("t.txt"), dir.file("t.csv"));
  ASSERT_TRUE(writer) << writer.error();
  PoseEstimate far = test::samplePose();
  far.T_w_c = SE3(Eigen::Quaterniond::Identity(), Vec3(1e200, -1e200, 3));
  ASSERT_TRUE(writer->write(far));
  ASSERT_TRUE(writer->write(test::samplePose()));
  const auto trajectory = lines(dir.file("t.txt"));
  ASSERT_EQ(trajectory.size(), 2u) << text(dir.file("t.txt"));
  EXPECT_GT(trajectory[0].size(), 400u);
  std::istringstream first(trajectory[0]);
  double values[8];
  for (double& v : values) ASSERT_TRUE(first >> v) << trajectory[0];
  EXPECT_DOUBLE_EQ(values[1], 1e200);
  EXPECT_EQ(std::count(trajectory[1].begin(), trajectory[1].end(), ' '), 7) << trajectory[1];
  const auto csv = lines(dir.file("t.csv"));
  ASSERT_EQ(csv.size(), 3u);  // header and two poses
  EXPECT_EQ(std::count(csv[1].begin(), csv[1].end(), ','), 20) << csv[1];
  EXPECT_EQ(text(dir.file("t.txt")).back(), '\n');
}

TEST(PoseLogWriter, NonFiniteValuesAreRefusedNotWritten) {
  test::TempDir dir;
  auto writer = PoseLogWriter::open(dir.file("t.txt"), dir.file("t.csv"));
  ASSERT_TRUE(writer) << writer.error();
  PoseEstimate bad = test::samplePose();
  bad.T_w_c = SE3(Eigen::Quaterniond::Identity(), Vec3(std::nan(""), 0, 0));
  Status s = writer->write(bad);
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().find("not finite"), std::string::npos) << s.error();
  bad = test::samplePose();
  bad.latency_ms = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(writer->write(bad));
  bad = test::samplePose();
  bad.map_T_w_c = SE3(Eigen::Quaterniond::Identity(), Vec3(0, std::numeric_limits<double>::infinity(), 0));
  EXPECT_FALSE(writer->write(bad));
  EXPECT_EQ(writer->csvLines(), 0);
  const std::string all = text(dir.file("t.csv")) + text(dir.file("t.txt"));
  EXPECT_EQ(all.find("nan"), std::string::npos) << all;
  EXPECT_EQ(all.find("inf"), std::string::npos) << all;
}

// The map trajectory holds the vouched-for poses in the map, the CSV both poses and the part.
TEST(PoseLogWriter, MapTrajectoryHoldsThePosesInTheMap) {
  test::TempDir dir;
  auto writer = PoseLogWriter::open(dir.file("t.txt"), dir.file("t.csv"), dir.file("map.txt"));
  ASSERT_TRUE(writer) << writer.error();
  const PoseEstimate pose = test::samplePose();
  PoseEstimate lost = pose;
  lost.state = TrackingState::kLost;
  ASSERT_TRUE(writer->write(pose));
  ASSERT_TRUE(writer->write(lost));
  const auto map = lines(dir.file("map.txt"));
  ASSERT_EQ(map.size(), 1u) << text(dir.file("map.txt"));  // the lost pose is not vouched for
  std::istringstream in(map[0]);
  double v[8];
  for (double& x : v) ASSERT_TRUE(in >> x) << map[0];
  const Vec3 t = pose.map_T_w_c.translation();
  const Eigen::Quaterniond q = pose.map_T_w_c.rotation();
  EXPECT_NEAR(v[1], t.x(), 1e-8);
  EXPECT_NEAR(v[2], t.y(), 1e-8);
  EXPECT_NEAR(v[3], t.z(), 1e-8);
  EXPECT_NEAR(std::abs(v[4] * q.x() + v[5] * q.y() + v[6] * q.z() + v[7] * q.w()), 1.0, 1e-8);
  EXPECT_GT((pose.map_T_w_c.translation() - pose.T_w_c.translation()).norm(), 0.1);
  const auto csv = lines(dir.file("t.csv"));
  ASSERT_EQ(csv.size(), 3u);
  EXPECT_NE(csv[0].find(",map_tx,"), std::string::npos) << csv[0];
  EXPECT_EQ(csv[1].substr(csv[1].rfind(',') + 1), "42");  // samplePose's part
  // A map trajectory that cannot be created is an error, the others closed.
  EXPECT_FALSE(PoseLogWriter::open(dir.file("a.txt"), dir.file("a.csv"), dir.file("no/such/dir/map.txt")));
}

TEST(MapFilter, KeepsTheFirstMapAndCountsTheOthers) {
  MapFilter filter;
  EXPECT_TRUE(filter.accept(77));
  EXPECT_FALSE(filter.accept(88));
  EXPECT_TRUE(filter.accept(77));
  EXPECT_FALSE(filter.accept(99));
  EXPECT_FALSE(filter.accept(88));
  EXPECT_EQ(filter.mapId(), 77);
  EXPECT_EQ(filter.otherPoses(), 3);
  EXPECT_EQ(filter.describeOthers(), "3 poses of other maps (88 99)");
  MapFilter given(5);
  EXPECT_FALSE(given.accept(77));
  EXPECT_TRUE(given.accept(5));
}

}  // namespace
}  // namespace rgbdslam
