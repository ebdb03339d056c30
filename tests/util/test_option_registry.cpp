#include "rgbdslam/util/option_registry.h"

#include <gtest/gtest.h>

#include <fstream>

#include "rgbdslam/system/slam_system.h"
#include "test_support.h"

namespace rgbdslam {
namespace {

struct Sample {
  double rate = 30.0;
  int count = 5;
  bool enabled = true;
  std::string mode = "a";
  void bind(OptionRegistry* r) {
    r->bind("sample", "rate", &rate, 0.0, 100.0, "Hz", "a rate");
    r->bind("sample", "count", &count, 1, 10, "items", "a count");
    r->bind("sample", "enabled", &enabled, "a switch");
    r->bind("sample", "mode", &mode, {"a", "b"}, "a choice");
  }
};

std::string writeYaml(const test::TempDir& dir, const std::string& body) {
  const std::string path = dir.file("c.yaml");
  std::ofstream(path) << "%YAML:1.0\n" << body;
  return path;
}

TEST(OptionRegistry, LoadsKnownKeys) {
  test::TempDir dir;
  Sample s;
  OptionRegistry r;
  s.bind(&r);
  ASSERT_TRUE(r.load(writeYaml(dir, "sample:\n  rate: 12.5\n  count: 7\n  enabled: false\n  mode: b\n")));
  EXPECT_DOUBLE_EQ(s.rate, 12.5);
  EXPECT_EQ(s.count, 7);
  EXPECT_FALSE(s.enabled);
  EXPECT_EQ(s.mode, "b");
}

TEST(OptionRegistry, RejectsUnknownIllTypedAndOutOfRange) {
  test::TempDir dir;
  const char* bad[] = {"sample:\n  rte: 1\n", "other:\n  rate: 1\n", "sample:\n  rate: fast\n",
                       "sample:\n  count: 2.5\n", "sample:\n  count: 11\n", "sample:\n  mode: c\n",
                       "sample:\n  enabled: maybe\n"};
  for (const char* body : bad) {
    Sample s;
    OptionRegistry r;
    s.bind(&r);
    const Status loaded = r.load(writeYaml(dir, body));
    EXPECT_FALSE(loaded) << body;
    EXPECT_NE(loaded.error().find(dir.file("c.yaml")), std::string::npos) << loaded.error();
  }
}

TEST(OptionRegistry, CommandLineAssignments) {
  Sample s;
  OptionRegistry r;
  s.bind(&r);
  EXPECT_TRUE(r.set("sample.rate=50"));
  EXPECT_DOUBLE_EQ(s.rate, 50.0);
  EXPECT_FALSE(r.set("sample.rate=500"));
  EXPECT_FALSE(r.set("sample.nothing=1"));
  EXPECT_FALSE(r.set("rate=1"));
}

TEST(OptionRegistry, OneOptionFeedsEveryCopyBoundToIt) {
  double tracker_copy = 1.5, mapper_copy = 1.5;
  OptionRegistry r;
  r.bind("noise", "k", &tracker_copy, 0.0, 10.0, "px", "shared");
  r.bind("other", "x", &mapper_copy, 0.0, 10.0, "", "unrelated");
  r.bind("noise", "k", &mapper_copy, 0.0, 10.0, "px", "shared");
  ASSERT_TRUE(r.set("noise.k=2.5"));
  EXPECT_DOUBLE_EQ(tracker_copy, 2.5);
  EXPECT_DOUBLE_EQ(mapper_copy, 2.5);
  EXPECT_FALSE(r.set("noise.k=20"));
  // Listed once, sections in the order they were first bound.
  EXPECT_EQ(r.yamlText(), "%YAML:1.0\n\nnoise:\n  # shared [px]\n  k: 2.5\n\nother:\n"
                          "  # unrelated\n  x: 2.5\n");
}

TEST(OptionRegistry, BindsAnEnumerationByName) {
  enum class Solver { kDense, kSparse };
  Solver solver = Solver::kDense;
  OptionRegistry r;
  r.bind("s", "solver", &solver, {{"dense", Solver::kDense}, {"sparse", Solver::kSparse}}, "how");
  EXPECT_NE(r.describe().find("s.solver = dense [dense|sparse]"), std::string::npos);
  ASSERT_TRUE(r.set("s.solver=sparse"));
  EXPECT_EQ(solver, Solver::kSparse);
  EXPECT_FALSE(r.set("s.solver=cholesky"));
  EXPECT_EQ(solver, Solver::kSparse);
}

TEST(OptionRegistry, BindsAFreeNameWithinLcmsChannelRules) {
  std::string channel = "SLAM_MAP";
  OptionRegistry r;
  r.bindName("channels", "map", &channel, "maps to the tracker");
  EXPECT_NE(r.yamlText().find("  map: \"SLAM_MAP\"\n"), std::string::npos) << r.yamlText();
  ASSERT_TRUE(r.set("channels.map=DRONE2_MAP"));
  EXPECT_EQ(channel, "DRONE2_MAP");
  for (const std::string& bad : std::vector<std::string>{"", "TWO WORDS", "QUOTE\"D", "SLAM_MAP|X", "SLAM.*", std::string(64, 'A')}) {
    const Status s = r.set("channels.map=" + bad);
    ASSERT_FALSE(s) << bad;
    EXPECT_NE(s.error().find("channels.map: '"), std::string::npos) << s.error();
    EXPECT_EQ(channel, "DRONE2_MAP");
  }
  EXPECT_TRUE(r.set("channels.map=" + std::string(63, 'A')));
  EXPECT_TRUE(r.set("channels.map=drone-2/SLAM_MAP"));
}

}  // namespace
}  // namespace rgbdslam

namespace rgbdslam {
namespace {

// Issue 13: a configuration whose top level is a list aborted every process (an uncaught
// cv::Exception); contradictory ranges were accepted.
TEST(OptionRegistry, TopLevelListOrValueIsAnErrorNamingTheFile) {
  test::TempDir dir;
  for (const char* body : {"- sample\n- other\n", "- rate: 3\n", "just text\n"}) {
    Sample s;
    OptionRegistry r;
    s.bind(&r);
    const Status loaded = r.load(writeYaml(dir, body));
    ASSERT_FALSE(loaded) << body;
    EXPECT_NE(loaded.error().find(dir.file("c.yaml")), std::string::npos) << loaded.error();
  }
  SlamOptions slam;
  OptionRegistry r;
  slam.bind(&r);
  const Status loaded = r.load(writeYaml(dir, "- tracker\n- mapper\n"));
  ASSERT_FALSE(loaded);
  EXPECT_NE(loaded.error().find("top level must be a mapping"), std::string::npos) << loaded.error();
}

// Found by fuzz_config (minimised): OpenCV's YAML parser threw std::length_error, which
// nothing caught (std::terminate).
TEST(OptionRegistry, ParserExceptionsOtherThanOpenCvsAreErrors) {
  test::TempDir dir;
  const std::string path = dir.file("c.yaml");
  std::ofstream(path) << "%YAML:1.\n n:0\n :";
  SlamOptions slam;
  OptionRegistry r;
  slam.bind(&r);
  const Status loaded = r.load(path);
  ASSERT_FALSE(loaded);
  EXPECT_NE(loaded.error().find(path), std::string::npos) << loaded.error();
}

TEST(OptionRegistry, ContradictoryRangesAreRejectedTogether) {
  SlamOptions slam;
  OptionRegistry r;
  slam.bind(&r);
  EXPECT_TRUE(r.validate()) << r.validate().error();
  const char* contradictions[] = {
      "mapper.keyframe_min_depth_m=9", "mapper.epipolar_min_depth_m=20", "tracker.keyframe_min_depth_m=9",
      "tracker.keyframe_max_depth_m=0.2", "tracker.quality_lost=0.9", "tracker.min_points_tracked=5000",
      "tracker.depth_points_per_level=0", "tracker.max_robust_sigma=0.1", "sync.resend_period_s=10"};
  for (const char* assignment : contradictions) {
    SlamOptions o;
    OptionRegistry registry;
    o.bind(&registry);
    ASSERT_TRUE(registry.set(assignment)) << assignment;  // each value alone is in range
    const Status valid = registry.validate();
    ASSERT_FALSE(valid) << assignment;
    const std::string key = std::string(assignment).substr(0, std::string(assignment).find('='));
    EXPECT_NE(valid.error().find(key), std::string::npos) << valid.error();
  }
  SlamOptions o;
  OptionRegistry registry;
  o.bind(&registry);
  ASSERT_TRUE(registry.set("mapper.keyframe_min_depth_m=9"));
  const Status valid = registry.validate();
  EXPECT_NE(valid.error().find("mapper.keyframe_min_depth_m = 9, mapper.keyframe_max_depth_m = 8"), std::string::npos)
      << valid.error();
  ASSERT_TRUE(registry.set("mapper.keyframe_max_depth_m=10"));
  EXPECT_TRUE(registry.validate());
}

}  // namespace
}  // namespace rgbdslam
