// write-sequence (test tool): writes a synthetic sequence as a TUM directory, or, with
// --eight-bit-depth FILE, rewrites a depth PNG as 8-bit (a bad-input case).
#include <iostream>
#include <opencv2/imgcodecs.hpp>

#include "rgbdslam/io/synthetic_scene.h"

using namespace rgbdslam;

int main(int argc, char** argv) {
  if (argc == 3 && std::string(argv[1]) == "--eight-bit-depth") {
    cv::Mat depth = cv::imread(argv[2], cv::IMREAD_UNCHANGED), eight;
    depth.convertTo(eight, CV_8U, 1.0 / 256.0);
    return cv::imwrite(argv[2], eight) ? 0 : 1;
  }
  if (argc != 3) {
    std::cerr << "usage: write-sequence SPEC DIR | --eight-bit-depth FILE\n";
    return 2;
  }
  auto options = parseSyntheticSpec(argv[1]);
  if (!options) return std::cerr << options.error() << "\n", 2;
  const Status written = SyntheticScene(*options).writeTumDirectory(argv[2]);
  if (!written) return std::cerr << written.error() << "\n", 1;
  return 0;
}
