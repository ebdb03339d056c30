// libFuzzer target: a TUM directory's lists. The input is rgb.txt, a NUL byte, depth.txt
// (no NUL: the same text for both); the folder holds rgb/1.png and depth/1.png (empty files:
// readTumIndex checks that listed files exist, decoding comes later).
#include <algorithm>
#include <filesystem>

#include "fuzz_support.h"
#include "rgbdslam/io/tum_dataset.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string dir = [] {
    const std::string path = rgbdslam::fuzz::scratchPath("tum");
    std::filesystem::create_directories(path + "/rgb");
    std::filesystem::create_directories(path + "/depth");
    rgbdslam::fuzz::writeFile(path + "/rgb/1.png", nullptr, 0);
    rgbdslam::fuzz::writeFile(path + "/depth/1.png", nullptr, 0);
    return path;
  }();
  const uint8_t* split = std::find(data, data + size, 0);
  rgbdslam::fuzz::writeFile(dir + "/rgb.txt", data, static_cast<size_t>(split - data));
  if (split == data + size) {
    rgbdslam::fuzz::writeFile(dir + "/depth.txt", data, size);
  } else {
    rgbdslam::fuzz::writeFile(dir + "/depth.txt", split + 1, static_cast<size_t>(data + size - split - 1));
  }
  (void)rgbdslam::readTumIndex(dir, rgbdslam::TumOptions{});
  return 0;
}
