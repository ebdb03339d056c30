// The loop audit against ground truth: a right edge, a lookalike's edge (the place it confuses
// 14 m away, as in synth:twins), a refused wrong edge, and keyframe times without a truth pose.
#include "rgbdslam/eval/loop_audit.h"

#include <gtest/gtest.h>

#include <cmath>

namespace rgbdslam {
namespace {

constexpr double kAuditStartS = 1341841873.0;  // TUM-like absolute stamps
constexpr double kAuditPeriodS = 1.0 / 30.0;

// A circle of radius 3 m flown in 20 s, the camera turning with it.
Trajectory auditTruth() {
  Trajectory truth;
  for (int k = 0; k < 600; ++k) {
    const double a = 2.0 * M_PI * k / 600.0;
    truth.push_back(TimedPose{kAuditStartS + k * kAuditPeriodS,
                              SE3(Mat3(Eigen::AngleAxisd(a, Vec3::UnitY())), Vec3(3.0 * std::cos(a), 0.0, 3.0 * std::sin(a)))});
  }
  return truth;
}

int64_t auditUtime(const Trajectory& truth, int k) { return static_cast<int64_t>(std::llround(truth[k].t * 1e6)); }

// The place recognised: frame 'a' seen from frame 'b', measured as 'T_a_b', with a verdict.
LoopClosureResult auditPlace(const Trajectory& truth, int a, int b, const SE3& T_a_b, bool refused) {
  LoopClosureResult r;
  r.place = PlaceStatus::kRecognised;
  r.closed = !refused;
  r.refused = refused;
  r.with_utime = auditUtime(truth, a);
  r.query_utime = auditUtime(truth, b);
  r.T_with_query = T_a_b;
  return r;
}

TEST(LoopAudit, TellsARightEdgeFromALookalikesAndCountsEachVerdict) {
  const Trajectory truth = auditTruth();
  const SE3 true_edge = truth[10].T_w_c.inverse() * truth[590].T_w_c;
  const SE3 noise(Mat3(Eigen::AngleAxisd(0.5 * M_PI / 180.0, Vec3::UnitX())), Vec3(0.02, -0.01, 0.015));
  // A lookalike room 14 m east: the query's view measured as if it stood in the first room.
  const auto lookalike = [&truth](int a, int b) {
    return truth[a].T_w_c.inverse() * truth[b].T_w_c * SE3(Mat3::Identity(), Vec3(14.0, 0.0, 0.0));
  };
  std::vector<LoopClosureResult> places = {
      auditPlace(truth, 10, 590, true_edge * noise, false),  // right, accepted
      auditPlace(truth, 20, 580, lookalike(20, 580), false),  // wrong, accepted
      auditPlace(truth, 30, 570, lookalike(30, 570), true),   // wrong, refused
  };
  LoopClosureResult unmatched = auditPlace(truth, 10, 590, true_edge, false);
  unmatched.query_utime += 1000000;  // a second after the truth ends
  places.push_back(unmatched);

  const LoopAuditOptions options;
  const LoopAudit audit = auditLoops(truth, places, options);
  EXPECT_EQ(audit.checked, 3);
  EXPECT_EQ(audit.unmatched, 1);
  EXPECT_EQ(audit.accepted, 2);
  EXPECT_EQ(audit.accepted_wrong, 1);
  EXPECT_EQ(audit.refused, 1);
  EXPECT_EQ(audit.refused_wrong, 1);
  EXPECT_NEAR(audit.right_max_error_m, noise.translation().norm(), 1e-6);
  EXPECT_NEAR(audit.right_max_error_deg, 0.5, 1e-6);
  EXPECT_NEAR(audit.accepted_max_error_m, 14.0, 1e-6);
  const std::string text = toKeyValueText(audit, options);
  EXPECT_NE(text.find("loops_accepted_wrong 1\n"), std::string::npos) << text;
  EXPECT_NE(text.find("loop_wrong_bar_m 0.250000\n"), std::string::npos) << text;
}

TEST(LoopAudit, TurnedPastTheBarIsWrongAtTheRightPosition) {
  const Trajectory truth = auditTruth();
  const SE3 true_edge = truth[100].T_w_c.inverse() * truth[400].T_w_c;
  const SE3 turned = true_edge * SE3(Mat3(Eigen::AngleAxisd(8.0 * M_PI / 180.0, Vec3::UnitY())), Vec3::Zero());
  double m = -1.0, deg = -1.0;
  ASSERT_TRUE(loopEdgeError(truth, auditUtime(truth, 100), auditUtime(truth, 400), turned, 0.02, &m, &deg));
  EXPECT_NEAR(m, 0.0, 1e-9);
  EXPECT_NEAR(deg, 8.0, 1e-6);
  const LoopAudit audit = auditLoops(truth, {auditPlace(truth, 100, 400, turned, false)});
  EXPECT_EQ(audit.accepted_wrong, 1);
  // A keyframe time 10 ms from a truth pose takes it; 50 ms from every one, none: not checked.
  EXPECT_TRUE(loopEdgeError(truth, auditUtime(truth, 100) + 10000, auditUtime(truth, 400), turned, 0.02, &m, &deg));
  EXPECT_NEAR(deg, 8.0, 1e-6);
  EXPECT_FALSE(loopEdgeError(truth, auditUtime(truth, 0) - 50000, auditUtime(truth, 400), turned, 0.02, &m, &deg));
}

}  // namespace
}  // namespace rgbdslam
