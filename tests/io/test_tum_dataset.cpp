#include "rgbdslam/io/tum_dataset.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "test_support.h"

namespace rgbdslam {
namespace {

namespace fs = std::filesystem;

PinholeCamera smallCamera() {
  PinholeCamera c;
  c.width = 32, c.height = 24, c.depth_factor = 5000, c.name = "small";
  return c;
}

// Writes a TUM directory with n colour/depth pairs, depth 5 ms after colour.
void writeSequence(const std::string& dir, int n, int width = 32, int height = 24) {
  fs::create_directories(dir + "/rgb");
  fs::create_directories(dir + "/depth");
  std::ofstream rgb(dir + "/rgb.txt"), depth(dir + "/depth.txt");
  rgb << "# colour images\n# file: test\n# timestamp filename\n";
  for (int i = 0; i < n; ++i) {
    const double t = 100.0 + i / 30.0;
    char name[64];
    std::snprintf(name, sizeof(name), "%.6f.png", t);
    cv::Mat colour(height, width, CV_8UC3, cv::Scalar(i, 2 * i, 3 * i));
    cv::Mat d(height, width, CV_16UC1, cv::Scalar(1000 + i));
    cv::imwrite(dir + "/rgb/" + name, colour);
    char dname[64];
    std::snprintf(dname, sizeof(dname), "%.6f.png", t + 0.005);
    cv::imwrite(dir + "/depth/" + dname, d);
    rgb << std::fixed << t << " rgb/" << name << "\n";
    depth << std::fixed << t + 0.005 << " depth/" << dname << "\n";
  }
}

TEST(TumDataset, ReadsAndAssociates) {
  test::TempDir dir;
  writeSequence(dir.path(), 5);
  auto source = openTumDataset(dir.path(), smallCamera());
  ASSERT_TRUE(source) << source.error();
  EXPECT_EQ((*source)->size(), 5u);
  EXPECT_NEAR((*source)->nominalRateHz(), 30.0, 1e-3);  // stamps have 1 us resolution
  for (int i = 0; i < 5; ++i) {
    FrameResult r = (*source)->next();
    ASSERT_EQ(r.status, FrameResult::Status::kFrame) << r.error;
    EXPECT_EQ(r.frame.seq, i);
    EXPECT_EQ(r.frame.colour.at<cv::Vec3b>(0, 0)[2], 3 * i);
    EXPECT_EQ(r.frame.depth.at<uint16_t>(3, 3), 1000 + i);
    EXPECT_EQ(r.frame.depth_scale, 5000.0);
    EXPECT_EQ(r.frame.utime, std::llround((100.0 + i / 30.0) * 1e6));
  }
  EXPECT_EQ((*source)->next().status, FrameResult::Status::kEnd);
}

TEST(TumDataset, MissingDirectoryIsNamed) {
  auto source = openTumDataset("/nonexistent/tum-seq", smallCamera());
  ASSERT_FALSE(source);
  EXPECT_NE(source.error().find("/nonexistent/tum-seq"), std::string::npos);
}

TEST(TumDataset, ListedFileThatDoesNotExistNamesTheLine) {
  test::TempDir dir;
  writeSequence(dir.path(), 3);
  std::ofstream(dir.path() + "/rgb.txt", std::ios::app) << "200.000000 rgb/missing.png\n";
  auto source = openTumDataset(dir.path(), smallCamera());
  ASSERT_FALSE(source);
  EXPECT_NE(source.error().find("rgb.txt:7"), std::string::npos) << source.error();
  EXPECT_NE(source.error().find("rgb/missing.png"), std::string::npos) << source.error();
}

TEST(TumDataset, MalformedLineIsNamed) {
  test::TempDir dir;
  writeSequence(dir.path(), 3);
  std::ofstream(dir.path() + "/depth.txt", std::ios::app) << "not-a-number depth/x.png\n";
  auto source = openTumDataset(dir.path(), smallCamera());
  ASSERT_FALSE(source);
  EXPECT_NE(source.error().find("depth.txt:4"), std::string::npos) << source.error();
}

TEST(TumDataset, TruncatedPngIsABadFrameAndReadingGoesOn) {
  test::TempDir dir;
  writeSequence(dir.path(), 3);
  auto entries = readTumIndex(dir.path(), {});
  ASSERT_TRUE(entries);
  const std::string victim = dir.path() + "/" + (*entries)[1].rgb_path;
  fs::resize_file(victim, fs::file_size(victim) / 2);
  auto source = openTumDataset(dir.path(), smallCamera());
  ASSERT_TRUE(source);
  EXPECT_EQ((*source)->next().status, FrameResult::Status::kFrame);
  FrameResult bad = (*source)->next();
  EXPECT_EQ(bad.status, FrameResult::Status::kBadFrame);
  EXPECT_NE(bad.error.find(victim), std::string::npos) << bad.error;
  EXPECT_EQ((*source)->next().status, FrameResult::Status::kFrame);
}

TEST(TumDataset, EightBitDepthIsRejectedByName) {
  test::TempDir dir;
  writeSequence(dir.path(), 2);
  auto entries = readTumIndex(dir.path(), {});
  const std::string victim = dir.path() + "/" + (*entries)[0].depth_path;
  cv::imwrite(victim, cv::Mat(24, 32, CV_8UC1, cv::Scalar(7)));
  auto source = openTumDataset(dir.path(), smallCamera());
  FrameResult bad = (*source)->next();
  EXPECT_EQ(bad.status, FrameResult::Status::kBadFrame);
  EXPECT_NE(bad.error.find("16-bit"), std::string::npos) << bad.error;
  EXPECT_NE(bad.error.find(victim), std::string::npos) << bad.error;
}

TEST(TumDataset, SizeDisagreeingWithCameraIsRejected) {
  test::TempDir dir;
  writeSequence(dir.path(), 2, 40, 30);
  auto source = openTumDataset(dir.path(), smallCamera());
  FrameResult bad = (*source)->next();
  EXPECT_EQ(bad.status, FrameResult::Status::kBadFrame);
  EXPECT_NE(bad.error.find("40x30"), std::string::npos) << bad.error;
  EXPECT_NE(bad.error.find("32x24"), std::string::npos) << bad.error;
}

TEST(TumDataset, NoDepthWithinToleranceIsAnError) {
  test::TempDir dir;
  writeSequence(dir.path(), 2);
  auto entries = readTumIndex(dir.path(), TumOptions{0.001, true});
  ASSERT_FALSE(entries);
}

TEST(TumDataset, ReadsTheSharedTeddySequenceExactly) {
  RGBDSLAM_REQUIRE_SHARED_DATA(dir, "tum_fr3_teddy_200");
  PinholeCamera camera;
  camera.name = "tum_fr3";
  auto source = openTumDataset(dir, camera);
  ASSERT_TRUE(source) << source.error();
  EXPECT_GE((*source)->size(), 190u);
  const TumEntry& e = (*source)->entries()[10];
  EXPECT_LE(std::abs(e.t_rgb - e.t_depth), 0.02);
  FrameResult r = (*source)->read(10);
  ASSERT_EQ(r.status, FrameResult::Status::kFrame) << r.error;
  const cv::Mat colour = cv::imread(dir + "/" + e.rgb_path, cv::IMREAD_COLOR);
  const cv::Mat depth = cv::imread(dir + "/" + e.depth_path, cv::IMREAD_UNCHANGED);
  EXPECT_EQ(cv::norm(colour, r.frame.colour, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(depth, r.frame.depth, cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace rgbdslam

namespace rgbdslam {
namespace {

// Issue 13: a symlink loop in a TUM directory threw std::filesystem::filesystem_error.
TEST(TumDataset, SymlinkLoopIsAnErrorNamingTheLine) {
  test::TempDir dir;
  writeSequence(dir.path(), 3);
  fs::create_symlink("loop_b.png", dir.path() + "/rgb/loop_a.png");
  fs::create_symlink("loop_a.png", dir.path() + "/rgb/loop_b.png");
  std::ofstream(dir.path() + "/rgb.txt", std::ios::app) << "200.000000 rgb/loop_a.png\n";
  auto source = openTumDataset(dir.path(), smallCamera());
  ASSERT_FALSE(source);
  EXPECT_NE(source.error().find("rgb.txt:7"), std::string::npos) << source.error();
  EXPECT_NE(source.error().find("rgb/loop_a.png"), std::string::npos) << source.error();
  test::TempDir looped;
  fs::create_symlink(looped.path() + "/self", looped.path() + "/self");
  EXPECT_FALSE(openTumDataset(looped.path() + "/self", smallCamera()));
}

// Issue 13: timestamps of 1e13 s overflowed into negative frame times.
TEST(TumDataset, TimestampsBeyondTheBoundAreRejected) {
  for (const char* stamp : {"1e13", "-5", "9.3e12"}) {
    test::TempDir dir;
    writeSequence(dir.path(), 3);
    std::ifstream listed(dir.path() + "/depth.txt");
    std::string first_time, existing;  // a file that exists: only the stamp is wrong
    listed >> first_time >> existing;
    std::ofstream(dir.path() + "/depth.txt", std::ios::app) << stamp << " " << existing << "\n";
    auto source = openTumDataset(dir.path(), smallCamera());
    ASSERT_FALSE(source) << stamp;
    EXPECT_NE(source.error().find("depth.txt:4"), std::string::npos) << source.error();
    EXPECT_NE(source.error().find("outside [0,"), std::string::npos) << source.error();
  }
}

}  // namespace
}  // namespace rgbdslam
