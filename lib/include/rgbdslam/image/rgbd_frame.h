#pragma once
// One registered colour + depth frame, the input of every algorithm.
// Depth is kept in the sensor's raw 16-bit units so it can be passed on losslessly;
// depthMetres() converts. A raw value of 0 means no reading.
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>

namespace rgbdslam {

struct RgbdFrame {
  int64_t utime = 0;        // acquisition time, host clock [us]
  int64_t seq = 0;          // sequence number from the source
  cv::Mat colour;           // CV_8UC3, BGR; may be empty for depth-only sources
  cv::Mat depth;            // CV_16UC1 raw units, 0 = no reading; may be empty
  double depth_scale = 5000.0;  // raw depth units per metre
  std::string camera_name;  // calibration name

  int width() const { return colour.empty() ? depth.cols : colour.cols; }
  int height() const { return colour.empty() ? depth.rows : colour.rows; }
  // Depth in metres, CV_32FC1, NaN where there is no reading.
  cv::Mat depthMetres() const;
  // Grey image (CV_8UC1) from the colour image.
  cv::Mat grey() const;
};

}  // namespace rgbdslam
