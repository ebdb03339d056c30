#include "rgbdslam/image/corners.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace rgbdslam {
namespace {

constexpr int kCircleSize = 16;  // pixels on the Bresenham circle of radius 3
constexpr int kArcLength = 10;   // FAST-10 (as PTAM): contiguous pixels needed
constexpr int kCircleRadius = 3;  // [px]
// The circle, clockwise from the top, as (dx, dy).
constexpr int kCircle[kCircleSize][2] = {{0, -3}, {1, -3}, {2, -2}, {3, -1}, {3, 0},  {3, 1},
                                         {2, 2},  {1, 3},  {0, 3},  {-1, 3}, {-2, 2}, {-3, 1},
                                         {-3, 0}, {-3, -1}, {-2, -2}, {-1, -3}};

// Largest t such that 10 contiguous circle pixels all differ from the centre by more than t
// (all brighter or all darker): max over arcs of the arc's minimum difference, minus one.
// Written as fixed-size int16 loops over the 16 arc starts, which compilers vectorise.
int fastScoreAt(const uint8_t* centre, const int* offsets) {
  constexpr int kWrapped = 2 * kCircleSize;  // the circle twice, so arcs need no modulo
  int16_t diff[kWrapped];
  const int c = centre[0];
  for (int k = 0; k < kCircleSize; ++k) {
    diff[k] = diff[k + kCircleSize] = static_cast<int16_t>(centre[offsets[k]] - c);
  }
  int16_t arc_min[kCircleSize], arc_max[kCircleSize];
  for (int k = 0; k < kCircleSize; ++k) {
    int16_t lo = diff[k], hi = diff[k];
    for (int j = 1; j < kArcLength; ++j) {
      lo = std::min(lo, diff[k + j]);
      hi = std::max(hi, diff[k + j]);
    }
    arc_min[k] = lo;
    arc_max[k] = hi;
  }
  int bright = arc_min[0], dark = -arc_max[0];  // best arc: (pixel - centre), (centre - pixel)
  for (int k = 1; k < kCircleSize; ++k) {
    bright = std::max<int>(bright, arc_min[k]);
    dark = std::max<int>(dark, -arc_max[k]);
  }
  return std::max(bright, dark) - 1;
}

void circleOffsets(const cv::Mat& image, int* offsets) {
  const int stride = static_cast<int>(image.step[0]);
  for (int k = 0; k < kCircleSize; ++k) offsets[k] = kCircle[k][1] * stride + kCircle[k][0];
}

// Whether corner i (at column x) is beaten by a corner of another row within one column of
// it, among all[*cursor .. end). The row is sorted by x and the caller's x only grows, so
// *cursor only moves forward. Ties: a corner earlier in raster order (earlier_row) wins.
bool beatenInRow(const std::vector<cv::Point2i>& all, const std::vector<int>& scores, int i,
                 int* cursor, int end, bool earlier_row) {
  const int x = all[i].x;
  while (*cursor < end && all[*cursor].x < x - 1) ++*cursor;
  for (int j = *cursor; j < end && all[j].x <= x + 1; ++j) {
    if (scores[j] > scores[i] || (earlier_row && scores[j] == scores[i])) return true;
  }
  return false;
}

// --- Detector, in two stages.
// Stage 1 rejects pixels with necessary conditions for a 10-arc of brighter (or darker)
// pixels: (a) the compass test: the arc contains circle pixel 0 or 8, and 4 or 12;
// (b) the even test: the arc contains 5 cyclically consecutive even-indexed circle pixels.
// On x86-64 (SSE2 is part of the base instruction set) 16 pixels are tested at once: (a)
// for all, (b) only for blocks where (a) passed somewhere (about 30 % at level 0 of a
// textured 640x480 image). Elsewhere, and for the last pixels of a row, the scalar compass
// test (a) is used. Stage 2 is the exact 10-of-16 test on the remaining pixels.
constexpr int kMaxGrey = 255;
// Circle indices of the compass pixels.
constexpr int kNorth = 0, kEast = 4, kSouth = 8, kWest = 12;
constexpr int kEvenCount = kCircleSize / 2;  // even pixels 0, 2, .., 14
constexpr int kEvenRun = 5;                  // consecutive even pixels in any 10-arc

bool passesCompass(const uint8_t* centre, int threshold, const int* offsets) {
  const int high = centre[0] + threshold, low = centre[0] - threshold;
  const int n = centre[offsets[kNorth]], e = centre[offsets[kEast]];
  const int s = centre[offsets[kSouth]], w = centre[offsets[kWest]];
  const bool bright = (n > high || s > high) && (e > high || w > high);
  const bool dark = (n < low || s < low) && (e < low || w < low);
  return bright || dark;
}

// True if the 16-bit cyclic mask has kArcLength (10) consecutive set bits.
inline bool hasArc(uint32_t mask16) {
  constexpr uint32_t kStarts = (1u << kCircleSize) - 1;  // arcs may start at bits 0..15
  const uint32_t m = mask16 | (mask16 << kCircleSize);
  uint32_t run = m & (m >> 1);  // runs of 2
  run &= run >> 2;              // runs of 4
  run &= run >> 4;              // runs of 8
  run &= run >> 2;              // runs of 10
  return (run & kStarts) != 0;
}

bool isCorner(const uint8_t* centre, int threshold, const int* offsets) {
  const int high = centre[0] + threshold;
  const int low = centre[0] - threshold;
  uint32_t bright = 0, dark = 0;
  for (int k = 0; k < kCircleSize; ++k) {
    const int q = centre[offsets[k]];
    bright |= static_cast<uint32_t>(q > high) << k;
    dark |= static_cast<uint32_t>(q < low) << k;
  }
  return hasArc(bright) || hasArc(dark);
}

#if defined(__SSE2__)
constexpr int kLanes = 16;  // pixels per SSE2 block

// Stage 1 for the 16 pixels at p: bit i set if p[i] is a candidate.
uint32_t candidateMaskSse2(const uint8_t* p, __m128i t, const int* offsets) {
  const __m128i zero = _mm_setzero_si128();
  constexpr int kAllLanes = 0xFFFF;
  const __m128i c = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
  const __m128i high = _mm_adds_epu8(c, t), low = _mm_subs_epu8(c, t);
  // 0xFF where circle pixel k is not brighter (q <= high) / not darker (q >= low).
  auto notBright = [&](int k) {
    const __m128i q = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + offsets[k]));
    return _mm_cmpeq_epi8(_mm_subs_epu8(q, high), zero);
  };
  auto notDark = [&](int k) {
    const __m128i q = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + offsets[k]));
    return _mm_cmpeq_epi8(_mm_subs_epu8(low, q), zero);
  };
  // (a) fails for a polarity if both of 0/8 or both of 4/12 fail.
  const __m128i fail_bright = _mm_or_si128(_mm_and_si128(notBright(kNorth), notBright(kSouth)),
                                           _mm_and_si128(notBright(kEast), notBright(kWest)));
  const __m128i fail_dark = _mm_or_si128(_mm_and_si128(notDark(kNorth), notDark(kSouth)),
                                         _mm_and_si128(notDark(kEast), notDark(kWest)));
  if (_mm_movemask_epi8(_mm_and_si128(fail_bright, fail_dark)) == kAllLanes) return 0;
  // (b) fails for a polarity if every window of 5 consecutive even pixels has a "not".
  __m128i nb[kEvenCount], nd[kEvenCount];
  for (int k = 0; k < kEvenCount; ++k) {
    nb[k] = notBright(2 * k);
    nd[k] = notDark(2 * k);
  }
  __m128i every_bright = _mm_cmpeq_epi8(zero, zero), every_dark = every_bright;
  for (int k = 0; k < kEvenCount; ++k) {
    __m128i any_b = nb[k], any_d = nd[k];
    for (int j = 1; j < kEvenRun; ++j) {
      any_b = _mm_or_si128(any_b, nb[(k + j) % kEvenCount]);
      any_d = _mm_or_si128(any_d, nd[(k + j) % kEvenCount]);
    }
    every_bright = _mm_and_si128(every_bright, any_b);
    every_dark = _mm_and_si128(every_dark, any_d);
  }
  // A candidate unless both polarities fail.
  return static_cast<uint32_t>(kAllLanes & ~_mm_movemask_epi8(_mm_and_si128(every_bright, every_dark)));
}
#endif

// Appends the corners of row y with x in [x_begin, x_end), in column order.
void detectRow(const uint8_t* row, int x_begin, int x_end, int y, int threshold,
               const int* offsets, std::vector<cv::Point2i>* out) {
  int x = x_begin;
#if defined(__SSE2__)
  const __m128i t = _mm_set1_epi8(static_cast<char>(threshold));
  for (; x + kLanes <= x_end; x += kLanes) {
    for (uint32_t mask = candidateMaskSse2(row + x, t, offsets); mask != 0; mask &= mask - 1) {
      const int xi = x + __builtin_ctz(mask);
      if (isCorner(row + xi, threshold, offsets)) out->emplace_back(xi, y);
    }
  }
#endif
  for (; x < x_end; ++x) {
    if (passesCompass(row + x, threshold, offsets) && isCorner(row + x, threshold, offsets)) {
      out->emplace_back(x, y);
    }
  }
}

}  // namespace

int fastScore(const cv::Mat& image, cv::Point2i p) {
  assert(image.type() == CV_8UC1);
  assert(p.x >= kCircleRadius && p.y >= kCircleRadius && p.x < image.cols - kCircleRadius &&
         p.y < image.rows - kCircleRadius);
  int offsets[kCircleSize];
  circleOffsets(image, offsets);
  return fastScoreAt(image.ptr<uint8_t>(p.y) + p.x, offsets);
}

void detectFastCorners(const cv::Mat& level_image, int threshold, int border,
                       LevelCorners* out) {
  assert(level_image.type() == CV_8UC1);
  assert(threshold >= 0 && threshold <= kMaxGrey);
  const int margin = std::max(border, kCircleRadius);
  const int x_begin = margin;
  const int x_end = level_image.cols - margin;
  const int y_end = level_image.rows - margin;
  int offsets[kCircleSize];
  circleOffsets(level_image, offsets);
  out->all.clear();
  for (int y = margin; y < y_end; ++y) {
    detectRow(level_image.ptr<uint8_t>(y), x_begin, x_end, y, threshold, offsets, &out->all);
  }
  const int rows = level_image.rows;
  out->row_start.assign(rows + 1, 0);
  for (const cv::Point2i& p : out->all) ++out->row_start[p.y + 1];
  for (int y = 0; y < rows; ++y) out->row_start[y + 1] += out->row_start[y];
  out->scores.clear();
  out->maxima.clear();
}

void computeMaxima(const cv::Mat& level_image, LevelCorners* corners) {
  assert(corners->rows() == level_image.rows);
  int offsets[kCircleSize];
  circleOffsets(level_image, offsets);
  const std::vector<cv::Point2i>& all = corners->all;
  const int count = static_cast<int>(all.size());
  corners->scores.resize(count);
  for (int i = 0; i < count; ++i) {
    corners->scores[i] = fastScoreAt(level_image.ptr<uint8_t>(all[i].y) + all[i].x, offsets);
  }
  corners->maxima.clear();
  const std::vector<int>& row_start = corners->row_start;
  const std::vector<int>& scores = corners->scores;
  const int rows = corners->rows();
  for (int y = 0; y < rows; ++y) {
    const int begin = row_start[y], end = row_start[y + 1];
    int above = y > 0 ? row_start[y - 1] : begin;   // cursor in row y - 1
    int below = end;                                // cursor in row y + 1
    const int below_end = y + 1 < rows ? row_start[y + 2] : end;
    for (int i = begin; i < end; ++i) {
      const int x = all[i].x;
      // Same row: the left neighbour is earlier (wins ties), the right one later.
      if (i > begin && all[i - 1].x == x - 1 && scores[i - 1] >= scores[i]) continue;
      if (i + 1 < end && all[i + 1].x == x + 1 && scores[i + 1] > scores[i]) continue;
      if (beatenInRow(all, scores, i, &above, begin, /*earlier_row=*/true)) continue;
      if (beatenInRow(all, scores, i, &below, below_end, /*earlier_row=*/false)) continue;
      corners->maxima.push_back(all[i]);
    }
  }
}

void detectCorners(const cv::Mat& level_image, int threshold, int border, LevelCorners* out) {
  detectFastCorners(level_image, threshold, border, out);
  computeMaxima(level_image, out);
}

void detectPyramidCorners(const ImagePyramid& pyramid, const CornerOptions& options,
                          bool with_maxima, std::vector<LevelCorners>* out) {
  out->resize(pyramid.levels.size());
  for (int level = 0; level < pyramid.numLevels(); ++level) {
    detectFastCorners(pyramid.levels[level], options.fast_thresholds[level], options.border,
                      &(*out)[level]);
    if (with_maxima) computeMaxima(pyramid.levels[level], &(*out)[level]);
  }
}

CornerOptions lossyCornerOptions(CornerOptions options, int margin) {
  for (int& threshold : options.fast_thresholds) threshold = std::max(1, threshold - margin);
  return options;
}

cv::Mat cornerBlockMask(const std::vector<LevelCorners>& corners, int step, cv::Size size) {
  step = std::max(step, 1);
  const int cols = (size.width + step - 1) / step, rows = (size.height + step - 1) / step;
  cv::Mat mask(rows, cols, CV_8UC1, cv::Scalar(0));
  if (cols == 0 || rows == 0) return mask;
  for (size_t level = 0; level < corners.size(); ++level) {
    const double scale = levelScale(static_cast<int>(level));
    const double reach = scale + 1.0;  // [level-0 px]
    for (const cv::Point2i& c : corners[level].all) {
      // The corner's level-0 position (pyramid.h, zeroFromLevel) and the blocks it reaches.
      const double u = (c.x + 0.5) * scale - 0.5, v = (c.y + 0.5) * scale - 0.5;
      const int u0 = std::clamp(static_cast<int>(std::floor((u - reach) / step)), 0, cols - 1);
      const int u1 = std::clamp(static_cast<int>(std::floor((u + reach) / step)), 0, cols - 1);
      const int v0 = std::clamp(static_cast<int>(std::floor((v - reach) / step)), 0, rows - 1);
      const int v1 = std::clamp(static_cast<int>(std::floor((v + reach) / step)), 0, rows - 1);
      mask(cv::Range(v0, v1 + 1), cv::Range(u0, u1 + 1)).setTo(255);
    }
  }
  return mask;
}

float shiTomasiScore(const cv::Mat& image, cv::Point2i p, int half_window) {
  assert(image.type() == CV_8UC1);
  const int reach = half_window + 1;  // window plus the central-difference margin [px]
  if (p.x < reach || p.y < reach || p.x >= image.cols - reach || p.y >= image.rows - reach) {
    return 0.0f;
  }
  // Sums of products of doubled gradients (2 * central difference, integers).
  int64_t sxx = 0, syy = 0, sxy = 0;
  const int stride = static_cast<int>(image.step[0]);
  for (int y = p.y - half_window; y <= p.y + half_window; ++y) {
    const uint8_t* row = image.ptr<uint8_t>(y);
    for (int x = p.x - half_window; x <= p.x + half_window; ++x) {
      const int gx = row[x + 1] - row[x - 1];
      const int gy = row[x + stride] - row[x - stride];
      sxx += gx * gx;
      syy += gy * gy;
      sxy += gx * gy;
    }
  }
  const int side = 2 * half_window + 1;
  // Undo the doubling (factor 4 on products) and average over the window.
  const double norm = 1.0 / (4.0 * side * side);
  const double a = sxx * norm, b = sxy * norm, c = syy * norm;
  const double half_trace = 0.5 * (a + c);
  const double half_diff = 0.5 * (a - c);
  return static_cast<float>(half_trace - std::sqrt(half_diff * half_diff + b * b));
}

double imageNoiseSigma(const cv::Mat& image) {
  assert(image.type() == CV_8UC1);
  if (image.cols < 3 || image.rows < 3) return 0.0;
  int64_t sum = 0, count = 0;
  for (int y = 1; y < image.rows - 1; y += 2) {
    const uint8_t* up = image.ptr<uint8_t>(y - 1);
    const uint8_t* row = image.ptr<uint8_t>(y);
    const uint8_t* down = image.ptr<uint8_t>(y + 1);
    for (int x = 1; x < image.cols - 1; ++x) {
      const int r = up[x - 1] - 2 * up[x] + up[x + 1] - 2 * row[x - 1] + 4 * row[x] - 2 * row[x + 1] +
                    down[x - 1] - 2 * down[x] + down[x + 1];
      sum += r < 0 ? -r : r;
    }
    count += image.cols - 2;
  }
  // The operator's response to unit-variance noise has standard deviation 6; the mean of a
  // Gaussian's absolute value is sqrt(2 / pi) times its standard deviation.
  return std::sqrt(M_PI / 2.0) * static_cast<double>(sum) / (6.0 * static_cast<double>(count));
}

}  // namespace rgbdslam
