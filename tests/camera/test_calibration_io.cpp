#include "rgbdslam/camera/calibration_io.h"

#include <gtest/gtest.h>

#include <fstream>

#include "test_support.h"

namespace rgbdslam {
namespace {

std::string writeFile(const test::TempDir& dir, const std::string& name, const std::string& text) {
  const std::string path = dir.file(name);
  std::ofstream(path) << text;
  return path;
}

TEST(CalibrationIo, LoadsTheShippedCameras) {
  const std::string source = test::sourceDir();
  for (const char* name : {"tum_fr1", "tum_fr2", "tum_fr3", "kinect_default"}) {
    auto camera = loadCamera(source + "/config/cameras/" + name + ".yaml");
    ASSERT_TRUE(camera) << camera.error();
    EXPECT_EQ(camera->name, name);
    EXPECT_EQ(camera->width, 640);
  }
  auto fr3 = loadCamera(source + "/config/cameras/tum_fr3.yaml");
  EXPECT_DOUBLE_EQ(fr3->fx, 535.4);
  EXPECT_DOUBLE_EQ(fr3->depth_factor, 5000.0);
  auto fr1 = loadCamera(source + "/config/cameras/tum_fr1.yaml");
  EXPECT_DOUBLE_EQ(fr1->k3, 1.1633);
}

TEST(CalibrationIo, AcceptsOrbSlamKeys) {
  test::TempDir dir;
  const std::string path = writeFile(dir, "orb.yaml",
                                     "%YAML:1.0\nCamera.fx: 517.3\nCamera.fy: 516.5\nCamera.cx: 318.6\n"
                                     "Camera.cy: 255.3\nCamera.k1: 0.26\nCamera.k2: -0.95\nCamera.p1: -0.005\n"
                                     "Camera.p2: 0.002\nCamera.k3: 1.16\nCamera.width: 640\nCamera.height: 480\n"
                                     "Camera.fps: 30.0\nDepthMapFactor: 5000.0\nORBextractor.nFeatures: 1000\n");
  auto camera = loadCamera(path);
  ASSERT_TRUE(camera) << camera.error();
  EXPECT_DOUBLE_EQ(camera->fx, 517.3);
  EXPECT_DOUBLE_EQ(camera->k2, -0.95);
  EXPECT_DOUBLE_EQ(camera->depth_factor, 5000.0);
  EXPECT_EQ(camera->name, "orb");
}

TEST(CalibrationIo, MissingKeyIsNamedWithTheFile) {
  test::TempDir dir;
  const std::string path = writeFile(dir, "nofy.yaml",
                                     "%YAML:1.0\nfx: 500\ncx: 320\ncy: 240\nimage_width: 640\n"
                                     "image_height: 480\ndepth_factor: 5000\n");
  auto camera = loadCamera(path);
  ASSERT_FALSE(camera);
  EXPECT_NE(camera.error().find("'fy'"), std::string::npos) << camera.error();
  EXPECT_NE(camera.error().find(path), std::string::npos) << camera.error();
}

TEST(CalibrationIo, IllTypedKeyIsNamed) {
  test::TempDir dir;
  const std::string path = writeFile(dir, "bad.yaml",
                                     "%YAML:1.0\nfx: \"five hundred\"\nfy: 500\ncx: 320\ncy: 240\n"
                                     "image_width: 640\nimage_height: 480\ndepth_factor: 5000\n");
  auto camera = loadCamera(path);
  ASSERT_FALSE(camera);
  EXPECT_NE(camera.error().find("'fx' is not a number"), std::string::npos) << camera.error();
}

TEST(CalibrationIo, MissingOrCorruptFileIsAnError) {
  test::TempDir dir;
  EXPECT_FALSE(loadCamera(dir.file("none.yaml")));
  const std::string path = writeFile(dir, "corrupt.yaml", "%YAML:1.0\nfx: [1, 2\n  : : {\n");
  auto camera = loadCamera(path);
  ASSERT_FALSE(camera);
  EXPECT_NE(camera.error().find(path), std::string::npos);
}

TEST(CalibrationIo, BadDistortionListIsAnError) {
  test::TempDir dir;
  const std::string path = writeFile(dir, "dist.yaml",
                                     "%YAML:1.0\nfx: 500\nfy: 500\ncx: 320\ncy: 240\nimage_width: 640\n"
                                     "image_height: 480\ndepth_factor: 5000\ndistortion: [0.1, 0.2]\n");
  auto camera = loadCamera(path);
  ASSERT_FALSE(camera);
  EXPECT_NE(camera.error().find("distortion"), std::string::npos);
}

}  // namespace
}  // namespace rgbdslam

namespace rgbdslam {
namespace {

// Issue 13: a camera file whose top level is a list aborted every process (an uncaught
// cv::Exception); image_width 1e12 said "must be positive".
TEST(CalibrationIo, TopLevelListOrValueIsAnErrorNamingTheFile) {
  test::TempDir dir;
  for (const char* body : {"%YAML:1.0\n- fx: 500\n- fy: 500\n", "- 1\n- 2\n", "%YAML:1.0\n--- 42\n"}) {
    const std::string path = writeFile(dir, "list.yaml", body);
    auto camera = loadCamera(path);
    ASSERT_FALSE(camera) << body;
    EXPECT_NE(camera.error().find(path), std::string::npos) << camera.error();
  }
}

TEST(CalibrationIo, ImageSizeBeyondAnIntSaysWhatIsWrong) {
  test::TempDir dir;
  const std::string base = "%YAML:1.0\nfx: 500\nfy: 500\ncx: 320\ncy: 240\ndepth_factor: 5000\nimage_height: 480\n";
  for (const char* width : {"1e12", "640.5", "-640", "0", "8193"}) {
    const std::string path = writeFile(dir, "wide.yaml", base + "image_width: " + width + "\n");
    auto camera = loadCamera(path);
    ASSERT_FALSE(camera) << width;
    EXPECT_NE(camera.error().find("'image_width'"), std::string::npos) << camera.error();
    EXPECT_NE(camera.error().find("whole number in [1, 8192]"), std::string::npos) << camera.error();
    EXPECT_EQ(camera.error().find("must be positive"), std::string::npos) << camera.error();
  }
}

}  // namespace
}  // namespace rgbdslam
