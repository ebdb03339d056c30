// libFuzzer target: a camera calibration file (loadCamera), as every process reads --camera.
#include "fuzz_support.h"
#include "rgbdslam/camera/calibration_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string path = rgbdslam::fuzz::scratchPath("camera.yaml");
  rgbdslam::fuzz::writeFile(path, data, size);
  (void)rgbdslam::loadCamera(path);
  return 0;
}
