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

namespace rgbdslam {
namespace {

// Issue 13: --max-backlog 4294967296 wrapped to 0 in an int; NaN or inf periods flooded or
// silenced messages.
TEST(CommandLine, RangesNonFiniteAndOverflowingNumbersAreErrors) {
  CommandLine cli = makeCli();
  cli.option("backlog", "N", "frames", "2");
  ASSERT_TRUE(parse(cli, {"x", "--backlog", "4294967296", "--rate", "nan"}));
  auto backlog = cli.getInt("backlog", 1, 1000);
  ASSERT_FALSE(backlog);
  EXPECT_EQ(backlog.error(), "--backlog: 4294967296 is outside [1, 1000]");
  auto rate = cli.getDouble("rate");
  ASSERT_FALSE(rate);
  EXPECT_NE(rate.error().find("not a finite number"), std::string::npos) << rate.error();
  for (const char* text : {"inf", "-inf", "1e999", "infinity"}) {
    CommandLine c = makeCli();
    ASSERT_TRUE(parse(c, {"x", "--rate", text}));
    EXPECT_FALSE(c.getDouble("rate")) << text;
  }
  CommandLine big = makeCli();
  ASSERT_TRUE(parse(big, {"x", "--rate", "99999999999999999999999"}));
  auto huge = big.getInt("rate");
  ASSERT_FALSE(huge);
  EXPECT_NE(huge.error().find("too large"), std::string::npos) << huge.error();
  CommandLine in_range = makeCli();
  ASSERT_TRUE(parse(in_range, {"x", "--rate", "0.5"}));
  EXPECT_FALSE(in_range.getDouble("rate", 1.0, kMaxPeriodS));
  EXPECT_DOUBLE_EQ(*in_range.getDouble("rate", 0.1, kMaxPeriodS), 0.5);
}

}  // namespace
}  // namespace rgbdslam
