#pragma once
// A keyframe's depth as the map keeps it: the raw 16-bit readings, read as metres on access.
//
// Why not metres in a float image: the mapper keeps every keyframe's depth for as long as
// the keyframe is in the map (new points, re-measured depths, loop closing), and at 640x480
// a float image is 1.23 MB, most of the ground station's memory per keyframe (a heap
// profile by allocation site, docs/open_work.md, session 41). The raw readings are half of
// that, and the conversion on access is the one depthToMetres makes (map.h), so every
// reading is the same float as before, bit for bit (at() between the readings of a depth kept
// at a step excepted, below).
//
// Block-constant depth is kept at its own step: a keyframe that came over the link with its
// depth at every 2nd, 4th or 8th pixel and row (procs/common/lcm_conversions.h) is decoded
// by repeating each reading over its step x step block; such an image is stored at the
// coarsest of those steps at which every block holds one value, which loses nothing (a
// quarter-step 640x480 depth: 38 kB instead of 1.23 MB). A sensor's full depth has no such
// blocks and stays at every pixel (unless it has no reading at all, as behind a covered
// lens: that is kept at the coarsest step, losslessly too). Depth kept at a step is read
// between its readings (at(), betweenReadings below): at the link's first rung that gave
// better trajectories than each block's own reading on 14 of 17 rendered sequences, and a
// worse one on the real teddy (docs/open_work.md, session 45).
//
// The raw image must not be written after a KeyframeDepth is made from it: kept at every
// pixel, it shares the buffer (the tracker and the mapper give it images of their own).
#include <cstddef>
#include <cstdint>
#include <limits>

#include <opencv2/core.hpp>

namespace rgbdslam {

// One raw reading in metres: NaN for 0 (no reading) and outside [min_m, max_m] [m].
// depthToMetres (map.h) and KeyframeDepth both convert with this, so they agree bit for bit.
inline float rawDepthToMetres(uint16_t units, double inv_scale, double min_m, double max_m) {
  const double d = units * inv_scale;
  return units != 0 && d >= min_m && d <= max_m ? static_cast<float>(d) : std::numeric_limits<float>::quiet_NaN();
}

class KeyframeDepth {
 public:
  KeyframeDepth() = default;
  // 'raw': CV_16UC1 at 'depth_scale' units per metre, 0 for no reading (or empty: no depth).
  // Readings nearer than min_m or farther than max_m [m] read as none. Keeps no reference
  // to 'raw' unless it is stored at every pixel (then it shares the buffer, as cv::Mat does).
  KeyframeDepth(const cv::Mat& raw, double depth_scale, double min_m, double max_m);

  bool empty() const { return raw_.empty(); }
  int cols() const { return cols_; }
  int rows() const { return rows_; }
  int step() const { return 1 << shift_; }  // pixels per stored reading along each axis (1, 2, 4, 8)
  size_t bytes() const { return raw_.total() * raw_.elemSize(); }

  // Depth [m] at pixel (u, v), inside the image; NaN where there is no valid reading. Kept at
  // a step, between readings that lie on one smooth surface the depth is interpolated, else
  // it is the block's own reading (betweenReadings).
  float at(int u, int v) const {
    if (shift_ == 0) return rawDepthToMetres(raw_.ptr<uint16_t>(v)[u], inv_scale_, min_m_, max_m_);
    return betweenReadings(u, v);
  }
  // The whole image as CV_32FC1 metres, NaN where there is no reading (empty if empty()):
  // the readings as kept, each over its block, not interpolated, so a map file that saves it
  // keeps the step and the readings (map/map_file.h) and the loop closer reads measured depth.
  cv::Mat metres() const;
  // The share of the image's pixels with a valid reading (0 if empty()).
  double validFraction() const;
  void release() { *this = KeyframeDepth(); }

 private:
  // Depth kept at a step: each block's reading was taken at the block's centre pixel, clipped
  // to the image in a last block cut by the border (procs/common/lcm_conversions.cpp,
  // subsampleDepth). A pixel between four readings gets their bilinear interpolation in
  // inverse depth, which is exact on a plane (inverse depth is affine in the pixel
  // coordinates there), when the four are valid and span at most
  // kInterpolateSpan of their depth: a wall seen at a grazing angle, along a corridor, changes
  // depth by a few percent a block, and the block's own reading would be off by up to half a
  // block's change. Where the four disagree more (an object's edge) or one is missing, the
  // pixel reads its own block's reading, as measured: a blend across an edge would invent a
  // surface that is not there.
  float betweenReadings(int u, int v) const;

  cv::Mat raw_;  // CV_16UC1, one reading per step x step block
  int shift_ = 0;  // log2 of the step
  int cols_ = 0, rows_ = 0;
  double inv_scale_ = 0.0;  // metres per raw unit
  double min_m_ = 0.0, max_m_ = 0.0;
};

}  // namespace rgbdslam
