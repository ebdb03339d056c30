#include "rgbdslam/io/trajectory_io.h"

#include <gtest/gtest.h>

#include <fstream>

#include "test_support.h"

namespace rgbdslam {
namespace {

TEST(TrajectoryIo, WriteThenReadRoundTrips) {
  test::TempDir dir;
  Trajectory trajectory;
  for (int i = 0; i < 10; ++i) {
    Vec6 xi;
    xi << 0.1 * i, -0.2, 0.3, 0.01 * i, 0.2, -0.1;
    trajectory.push_back({1305031102.175304 + i * 0.033, SE3::exp(xi)});
  }
  ASSERT_TRUE(writeTumTrajectory(dir.file("t.txt"), trajectory));
  auto back = readTumTrajectory(dir.file("t.txt"));
  ASSERT_TRUE(back) << back.error();
  ASSERT_EQ(back->size(), trajectory.size());
  for (size_t i = 0; i < trajectory.size(); ++i) {
    EXPECT_NEAR((*back)[i].t, trajectory[i].t, 1e-6);
    EXPECT_LT(((*back)[i].T_w_c.inverse() * trajectory[i].T_w_c).log().norm(), 1e-8);
  }
}

TEST(TrajectoryIo, MalformedLineNamesFileAndLine) {
  test::TempDir dir;
  std::ofstream(dir.file("bad.txt")) << "# header\n1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 1\n";
  auto trajectory = readTumTrajectory(dir.file("bad.txt"));
  ASSERT_FALSE(trajectory);
  EXPECT_NE(trajectory.error().find("bad.txt:3"), std::string::npos) << trajectory.error();
}

TEST(TrajectoryIo, RejectsNonUnitQuaternionAndTrailingText) {
  EXPECT_FALSE(parseTumLine("1.0 0 0 0 0 0 0 2"));
  EXPECT_FALSE(parseTumLine("1.0 0 0 0 0 0 0 1 extra"));
  EXPECT_FALSE(parseTumLine("1.0 nan 0 0 0 0 0 1"));
  EXPECT_TRUE(parseTumLine("1.0 0 0 0 0 0 0 1"));
}

}  // namespace
}  // namespace rgbdslam
