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

// The largest (max - min) / min of the four readings interpolated between: two depth edges in
// a room (an object 20 cm before a wall at 2 m) differ by 10 %, a corridor's wall at 5 m seen
// 1 m aside changes 4 % over a 4-pixel block.
constexpr double kInterpolateSpan = 0.08;

float KeyframeDepth::betweenReadings(int u, int v) const {
  const int step = 1 << shift_, half = step / 2;
  const float own = rawDepthToMetres(raw_.ptr<uint16_t>(v >> shift_)[u >> shift_], inv_scale_, min_m_, max_m_);
  // The reading at or before (u, v) along each axis, and the fraction of the way to the next.
  // Reading k was taken at pixel k step + half, clipped to the image (a last block of half a
  // step or less: subsampleDepth).
  const auto place = [&](int x, int count, int size, int* i0, double* t) {
    const auto centre = [&](int k) { return std::min(k * step + half, size - 1); };
    int before = x >= half ? std::min((x - half) / step, count - 1) : -1;
    if (before + 1 < count && centre(before + 1) <= x) ++before;
    if (before < 0 || before + 1 >= count) {
      *i0 = std::clamp(before, 0, count - 1);
      *t = 0.0;
      return;
    }
    *i0 = before;
    *t = static_cast<double>(x - centre(before)) / (centre(before + 1) - centre(before));
  };
  int i0 = 0, j0 = 0;
  double tu = 0.0, tv = 0.0;
  place(u, raw_.cols, cols_, &i0, &tu);
  place(v, raw_.rows, rows_, &j0, &tv);
  const int i1 = tu > 0.0 ? i0 + 1 : i0, j1 = tv > 0.0 ? j0 + 1 : j0;
  const float d[4] = {rawDepthToMetres(raw_.ptr<uint16_t>(j0)[i0], inv_scale_, min_m_, max_m_),
                      rawDepthToMetres(raw_.ptr<uint16_t>(j0)[i1], inv_scale_, min_m_, max_m_),
                      rawDepthToMetres(raw_.ptr<uint16_t>(j1)[i0], inv_scale_, min_m_, max_m_),
                      rawDepthToMetres(raw_.ptr<uint16_t>(j1)[i1], inv_scale_, min_m_, max_m_)};
  float lo = d[0], hi = d[0];
  for (const float x : d) {
    if (std::isnan(x)) return own;
    lo = std::min(lo, x), hi = std::max(hi, x);
  }
  if (hi - lo > kInterpolateSpan * lo) return own;
  const double w = (1 - tv) * ((1 - tu) / d[0] + tu / d[1]) + tv * ((1 - tu) / d[2] + tu / d[3]);
  return static_cast<float>(1.0 / w);
}

cv::Mat KeyframeDepth::metres() const {
  if (empty()) return cv::Mat();
  cv::Mat out(rows_, cols_, CV_32FC1);
  for (int v = 0; v < rows_; ++v) {
    const uint16_t* in = raw_.ptr<uint16_t>(v >> shift_);
    float* o = out.ptr<float>(v);
    for (int u = 0; u < cols_; ++u) o[u] = rawDepthToMetres(in[u >> shift_], inv_scale_, min_m_, max_m_);
  }
  return out;
}

}  // namespace rgbdslam
