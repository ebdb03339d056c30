#include "rgbdslam/image/rgbd_frame.h"

#include <limits>
#include <opencv2/imgproc.hpp>

namespace rgbdslam {

cv::Mat RgbdFrame::depthMetres() const {
  cv::Mat out(depth.size(), CV_32FC1);
  const float inv_scale = static_cast<float>(1.0 / depth_scale);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int v = 0; v < depth.rows; ++v) {
    const uint16_t* in_row = depth.ptr<uint16_t>(v);
    float* out_row = out.ptr<float>(v);
    for (int u = 0; u < depth.cols; ++u) out_row[u] = in_row[u] ? in_row[u] * inv_scale : nan;
  }
  return out;
}

cv::Mat RgbdFrame::grey() const {
  cv::Mat g;
  if (colour.channels() == 1) return colour;
  cv::cvtColor(colour, g, cv::COLOR_BGR2GRAY);
  return g;
}

}  // namespace rgbdslam
