#include "common/slam_config.h"

#include <gtest/gtest.h>

#include "test_support.h"

namespace rgbdslam {
namespace {

Expected<SlamConfig> load(std::vector<std::string> args) {
  CommandLine cli("prog", "Loads the configuration.");
  addSlamConfigOptions(cli);
  std::vector<char*> argv;
  static std::string program = "prog";
  argv.push_back(program.data());
  for (auto& a : args) argv.push_back(a.data());
  if (Status s = cli.parse(static_cast<int>(argv.size()), argv.data()); !s) return Error{s.error()};
  return loadSlamConfig(cli);
}

// config/slam.yaml documents every option of the suite, the processes' own included.
TEST(SlamConfig, ShippedFileMatchesTheDefaults) {
  auto defaults = load({});
  ASSERT_TRUE(defaults) << defaults.error();
  auto shipped = load({"--config", test::sourceDir() + "/config/slam.yaml"});
  ASSERT_TRUE(shipped) << shipped.error();
  EXPECT_EQ(shipped->registry->yamlText(), defaults->registry->yamlText())
      << "config/slam.yaml is out of date: regenerate it with rgbd-slam --print-config yaml";
  for (const char* section : {"\nchannels:\n", "\ntracker_node:\n", "\nmapper_node:\n", "\nsync:\n"}) {
    EXPECT_NE(defaults->registry->yamlText().find(section), std::string::npos) << section;
  }
}

TEST(SlamConfig, ProcessOptionsComeFromTheRegistryAndSetRepeats) {
  auto config = load({"--set", "channels.map=DRONE2_MAP,tracker_node.max_backlog_frames=5", "--set",
                      "tracker_node.keyframe_depth=half", "--set", "mapper_node.status_period_s=0.5",
                      "--mode", "mono"});
  ASSERT_TRUE(config) << config.error();
  EXPECT_EQ(config->procs->channels.map, "DRONE2_MAP");
  EXPECT_EQ(config->procs->channels.keyframe, ChannelOptions{}.keyframe);
  EXPECT_EQ(config->procs->tracker_node.max_backlog_frames, 5);
  EXPECT_EQ(config->procs->tracker_node.keyframe_encoding.depth_step, 2);
  EXPECT_DOUBLE_EQ(config->procs->mapper_node.status_period_s, 0.5);
  EXPECT_EQ(config->slam->mode, "mono");
}

TEST(SlamConfig, OutOfRangeProcessOptionsAreErrorsNamingTheKey) {
  for (const auto& [assignment, message] :
       std::vector<std::pair<std::string, std::string>>{
           {"tracker_node.max_backlog_frames=4294967296", "tracker_node.max_backlog_frames: 4294967296 is outside [1, 1000]"},
           {"tracker_node.status_period_s=nan", "tracker_node.status_period_s: 'nan' is not a number"},
           {"mapper_node.status_period_s=0", "mapper_node.status_period_s: 0 is outside"},
           {"channels.pose=TWO WORDS", "channels.pose: 'TWO WORDS' must be 1 to 63 letters, digits"},
           {"tracker_node.keyframe_grey=gif", "tracker_node.keyframe_grey: 'gif' is not one of jpeg|png"}}) {
    auto config = load({"--set", assignment});
    ASSERT_FALSE(config) << assignment;
    EXPECT_NE(config.error().find(message), std::string::npos) << config.error();
  }
}

}  // namespace
}  // namespace rgbdslam
