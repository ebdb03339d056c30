// eight-bit-depth (test tool): rewrites a 16-bit depth PNG as 8-bit, a bad-input case for
// the TUM reader. Usage: eight-bit-depth FILE
#include <iostream>
#include <opencv2/imgcodecs.hpp>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: eight-bit-depth FILE\n";
    return 2;
  }
  cv::Mat depth = cv::imread(argv[1], cv::IMREAD_UNCHANGED), eight;
  if (depth.empty()) return std::cerr << argv[1] << ": cannot read\n", 1;
  depth.convertTo(eight, CV_8U, 1.0 / 256.0);
  return cv::imwrite(argv[1], eight) ? 0 : 1;
}
