#include "rgbdslam/map/keyframe_depth.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace rgbdslam {
namespace {

// Whether every step x step block of 'raw' (the last ones clipped at the border) holds one
// value: each row equals its block's first row, and that row is constant over each block.
bool blockConstant(const cv::Mat& raw, int step) {
  const size_t row_bytes = static_cast<size_t>(raw.cols) * sizeof(uint16_t);
  for (int v = 0; v < raw.rows; ++v) {
    const uint16_t* row = raw.ptr<uint16_t>(v);
    if (v % step != 0) {
      if (std::memcmp(row, raw.ptr<uint16_t>(v - v % step), row_bytes) != 0) return false;
      continue;
    }
    for (int u = 0; u < raw.cols; ++u) {
      if (row[u] != row[u - u % step]) return false;
    }
  }
  return true;
}

}  // namespace

KeyframeDepth::KeyframeDepth(const cv::Mat& raw, double depth_scale, double min_m, double max_m)
    : cols_(raw.cols), rows_(raw.rows), inv_scale_(1.0 / depth_scale), min_m_(min_m), max_m_(max_m) {
  if (raw.empty()) {
    cols_ = rows_ = 0;
    return;
  }
  CV_Assert(raw.type() == CV_16UC1);
  for (const int shift : {3, 2, 1}) {
    const int step = 1 << shift;
    if (raw.cols < step || raw.rows < step || !blockConstant(raw, step)) continue;
    shift_ = shift;
    raw_.create((raw.rows + step - 1) / step, (raw.cols + step - 1) / step, CV_16UC1);
    for (int v = 0; v < raw_.rows; ++v) {
      const uint16_t* in = raw.ptr<uint16_t>(v * step);
      uint16_t* out = raw_.ptr<uint16_t>(v);
      for (int u = 0; u < raw_.cols; ++u) out[u] = in[u * step];
    }
    return;
  }
  raw_ = raw;
}

// Each stored reading counts for its block's pixels, the last row and column of blocks
// clipped at the image's border.
double KeyframeDepth::validFraction() const {
  if (empty()) return 0.0;
  const int step = 1 << shift_;
  int64_t valid = 0;
  for (int v = 0; v < raw_.rows; ++v) {
    const int block_rows = std::min(step, rows_ - v * step);
    const uint16_t* in = raw_.ptr<uint16_t>(v);
    for (int u = 0; u < raw_.cols; ++u) {
      if (std::isnan(rawDepthToMetres(in[u], inv_scale_, min_m_, max_m_))) continue;
      valid += static_cast<int64_t>(block_rows) * std::min(step, cols_ - u * step);
    }
  }
  return static_cast<double>(valid) / (static_cast<double>(cols_) * rows_);
}

cv::Mat KeyframeDepth::metres() const {
  if (empty()) return cv::Mat();
  cv::Mat out(rows_, cols_, CV_32FC1);
  for (int v = 0; v < rows_; ++v) {
    float* o = out.ptr<float>(v);
    for (int u = 0; u < cols_; ++u) o[u] = at(u, v);
  }
  return out;
}

}  // namespace rgbdslam
