#include "common/cli.h"

#include <gtest/gtest.h>

namespace rgbdslam {
namespace {

CommandLine makeCli() {
  CommandLine cli("prog", "Does things.");
  cli.option("rate", "HZ", "frames per second", "30");
  cli.flag("step", "one at a time");
  cli.positional("INPUT", "input file");
  addLcmUrlOption(cli);
  return cli;
}

Status parse(CommandLine& cli, std::vector<std::string> args) {
  std::vector<char*> argv;
  static std::string program = "prog";
  argv.push_back(program.data());
  for (auto& a : args) argv.push_back(a.data());
  return cli.parse(static_cast<int>(argv.size()), argv.data());
}

TEST(CommandLine, ParsesValuesFlagsAndPositionals) {
  CommandLine cli = makeCli();
  ASSERT_TRUE(parse(cli, {"in.txt", "--rate", "12.5", "--step"}));
  EXPECT_EQ(cli.positionalValue(0), "in.txt");
  EXPECT_DOUBLE_EQ(*cli.getDouble("rate"), 12.5);
  EXPECT_TRUE(cli.has("step"));
  EXPECT_EQ(cli.get("lcm-url"), kDefaultLcmUrl);
}

TEST(CommandLine, DefaultsAndEqualsForm) {
  CommandLine cli = makeCli();
  ASSERT_TRUE(parse(cli, {"--rate=7", "x"}));
  EXPECT_EQ(*cli.getInt("rate"), 7);
  CommandLine other = makeCli();
  ASSERT_TRUE(parse(other, {"x"}));
  EXPECT_EQ(*other.getInt("rate"), 30);
  EXPECT_FALSE(other.has("rate"));
}

TEST(CommandLine, RejectsUnknownMissingAndBadValues) {
  CommandLine a = makeCli();
  EXPECT_FALSE(parse(a, {"x", "--bogus"}));
  CommandLine b = makeCli();
  EXPECT_FALSE(parse(b, {"x", "--rate"}));
  CommandLine c = makeCli();
  EXPECT_FALSE(parse(c, {}));
  CommandLine d = makeCli();
  EXPECT_FALSE(parse(d, {"x", "y"}));
  CommandLine e = makeCli();
  ASSERT_TRUE(parse(e, {"x", "--rate", "fast"}));
  EXPECT_FALSE(e.getDouble("rate"));
}

TEST(CommandLine, HelpListsEveryOptionWithDefault) {
  CommandLine cli = makeCli();
  ASSERT_TRUE(parse(cli, {"--help"}));
  EXPECT_TRUE(cli.helpRequested());
  const std::string help = cli.helpText();
  EXPECT_NE(help.find("--rate HZ"), std::string::npos);
  EXPECT_NE(help.find("(default: 30)"), std::string::npos);
  EXPECT_NE(help.find("--lcm-url"), std::string::npos);
}

}  // namespace
}  // namespace rgbdslam
