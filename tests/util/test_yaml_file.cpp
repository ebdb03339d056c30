// The project's YAML reader (libyaml into a tree, with limits): what camera and
// configuration files may hold, and that every hostile construct is a bounded error.
#include "rgbdslam/util/yaml_file.h"

#include <gtest/gtest.h>

#include <fstream>

#include "rgbdslam/util/option_registry.h"
#include "rgbdslam/system/slam_system.h"
#include "test_support.h"

namespace rgbdslam {
namespace {

std::string errorOf(const std::string& text) {
  auto parsed = parseYaml(text, "f.yaml");
  return parsed ? "" : parsed.error();
}

TEST(YamlFile, ReadsOpenCvsLayoutSectionsFlowListsAcrossLinesAndQuotes) {
  auto root = parseYaml(
      "%YAML:1.0\n---\n# comment\nname: \"tum\"\nfx: 535.4\nwidth: 640\n"
      "distortion: [ 0.1, -0.2,\n  0.0, 0.0 ]\nlabel: '12'\n"
      "tracker:\n  rate: 3   # trailing comment\n  on: true\n"
      "T: !!opencv-matrix\n  rows: 1\n  data: [ 1. ]\n",
      "f.yaml");
  ASSERT_TRUE(root) << root.error();
  ASSERT_TRUE(root->isMapping());
  EXPECT_EQ(root->find("name")->scalar, "tum");
  EXPECT_DOUBLE_EQ(*root->find("fx")->number(), 535.4);
  EXPECT_EQ(root->find("fx")->line, 5);
  ASSERT_TRUE(root->find("distortion")->isSequence());
  EXPECT_EQ(root->find("distortion")->items.size(), 4u);
  EXPECT_DOUBLE_EQ(*root->find("distortion")->items[1].number(), -0.2);
  EXPECT_FALSE(root->find("label")->number()) << "quoted: a string";
  EXPECT_EQ(root->find("tracker")->find("rate")->scalar, "3");
  EXPECT_EQ(root->find("tracker")->find("on")->scalar, "true");
  EXPECT_EQ(root->find("T")->find("rows")->scalar, "1") << "the tag is ignored";
  EXPECT_EQ(root->find("missing"), nullptr);
}

TEST(YamlFile, NumbersAreWholeFiniteAndUnquoted) {
  auto root = parseYaml("a: 1e12\nb: .inf\nc: .nan\nd: 12abc\ne: 1e999\n", "f.yaml");
  ASSERT_TRUE(root) << root.error();
  EXPECT_DOUBLE_EQ(*root->find("a")->number(), 1e12);
  for (const char* key : {"b", "c", "d", "e"}) EXPECT_FALSE(root->find(key)->number()) << key;
}

TEST(YamlFile, HostileConstructsAreErrorsNamingTheLine) {
  EXPECT_NE(errorOf("a: 1\na: 2\n").find("f.yaml:2: key 'a' appears twice"), std::string::npos);
  EXPECT_NE(errorOf("a: &x [1, 2]\nb: *x\n").find("aliases"), std::string::npos);
  EXPECT_NE(errorOf("a: 1\n---\nb: 2\n").find("more than one document"), std::string::npos);
  EXPECT_NE(errorOf("? [1, 2]\n: 3\n").find("a key must be a plain name"), std::string::npos);
  EXPECT_NE(errorOf("a: [1, 2\n").find("f.yaml:"), std::string::npos);
  EXPECT_NE(errorOf("").find("is empty"), std::string::npos);
  EXPECT_NE(errorOf("a: \"\x01\"\n").find("control characters"), std::string::npos);
  // Deep nesting: 10 000 brackets would overflow a recursive reader's stack.
  EXPECT_NE(errorOf("a: " + std::string(10000, '[')).find("nested more than 16 deep"), std::string::npos);
  // Many nodes: bounded too.
  std::string wide = "a: [";
  for (int i = 0; i < 200000; ++i) wide += "1,";
  EXPECT_NE(errorOf(wide + "1]\n").find("more than 100000 nodes"), std::string::npos);
}

// Found by fuzz_config: a 1.9 kB mangled configuration on which OpenCV's parser never
// returned (its memory growing). Now an error, at once.
TEST(YamlFile, TheFileThatHungOpenCvsParserIsAnError) {
  const std::string path = test::sourceDir() + "/tests/data/hostile/config_opencv_hang.yaml";
  SlamOptions slam;
  OptionRegistry r;
  slam.bind(&r);
  const Status loaded = r.load(path);
  ASSERT_FALSE(loaded);
  EXPECT_NE(loaded.error().find(path + ":"), std::string::npos) << loaded.error();
}

TEST(YamlFile, LargeFilesAreRefusedBeforeTheyAreRead) {
  test::TempDir dir;
  const std::string path = dir.file("big.yaml");
  std::ofstream(path) << "a: \"" << std::string(2 << 20, 'x') << "\"\n";
  const Status read = readYamlMapping(path, "camera", "fx: ...", [](const YamlNode&) { return Status{}; });
  ASSERT_FALSE(read);
  EXPECT_NE(read.error().find("more than a camera file holds (1 MiB)"), std::string::npos) << read.error();
}

}  // namespace
}  // namespace rgbdslam
