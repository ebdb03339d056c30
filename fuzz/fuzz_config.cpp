// libFuzzer target: a SLAM configuration file (config/slam.yaml layout) through the option
// registry, then the rules between options, as loadSlamConfig does for --config.
#include "fuzz_support.h"
#include "rgbdslam/system/slam_system.h"
#include "rgbdslam/util/option_registry.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string path = rgbdslam::fuzz::scratchPath("slam.yaml");
  rgbdslam::fuzz::writeFile(path, data, size);
  rgbdslam::SlamOptions options;
  rgbdslam::OptionRegistry registry;
  options.bind(&registry);
  if (registry.load(path)) (void)registry.validate();
  return 0;
}
