#include "rgbdslam/image/patch.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cassert>
#include <climits>
#include <cmath>

namespace rgbdslam {
namespace {

constexpr double kMinAbsDeterminant = 1e-12;  // |det(A_cur_src)| below this: singular
constexpr double kAreaPerLevel = 4.0;          // pixel area ratio between adjacent levels
constexpr int kPaddedOffset = kPatchCentre + 1;  // padded (0, 0) is at offset (-5, -5)
constexpr float kRoundHalf = 0.5f;             // added before truncating to a grey level
// Smallest eigenvalue of the template's zero-mean gradient covariance, summed over the 64
// pixels, below which refinement is ill-posed [(grey levels / px)^2].
constexpr double kMinGradientEnergy = 1.0;

// Sum and sum of squares of the template.
void finishPatch(Patch* patch) {
  int sum = 0, sum_sq = 0;
  for (int i = 0; i < kPatchArea; ++i) {
    const int v = patch->pixels[i];
    sum += v;
    sum_sq += v * v;
  }
  patch->sum = sum;
  patch->sum_sq = sum_sq;
}

// Copies the inner 8x8 of 'padded' into 'pixels'.
void copyInner(Patch* patch) {
  for (int r = 0; r < kPatchSize; ++r) {
    for (int c = 0; c < kPatchSize; ++c) {
      patch->pixels[r * kPatchSize + c] = patch->padded[(r + 1) * kPaddedSize + c + 1];
    }
  }
}

inline bool insideForBilinear(const cv::Mat& image, const Eigen::Vector2d& p) {
  return p.x() >= 0.0 && p.y() >= 0.0 && p.x() <= image.cols - 1 && p.y() <= image.rows - 1;
}

}  // namespace

int chooseSearchLevel(const Eigen::Matrix2d& A_cur_src, int source_level, int num_levels) {
  double det = A_cur_src.determinant();
  if (!(det > 0.0)) return -1;
  det *= std::pow(kAreaPerLevel, source_level);
  int level = 0;
  while (det > kLevelUpDeterminant && level < num_levels - 1) {
    ++level;
    det /= kAreaPerLevel;
  }
  return level;
}

bool warpPatch(const cv::Mat& source_level_image, int source_level,
               const Eigen::Vector2d& source_uv_level0, const Eigen::Matrix2d& A_cur_src,
               int search_level, Patch* out) {
  assert(source_level_image.type() == CV_8UC1);
  if (search_level < 0 || std::abs(A_cur_src.determinant()) < kMinAbsDeterminant) {
    return false;
  }
  if (source_level_image.cols < 2 || source_level_image.rows < 2) return false;
  // Template offset [search-level px] -> source-level offset.
  const Eigen::Matrix2d M_src_tpl =
      A_cur_src.inverse() * (levelScale(search_level) / levelScale(source_level));
  const Eigen::Vector2d centre = levelFromZero(source_uv_level0, source_level);
  // The sampled region is the affine image of the padded square: check its four corners.
  const double lo = -kPaddedOffset, hi = kPaddedSize - 1 - kPaddedOffset;
  for (const Eigen::Vector2d& o : {Eigen::Vector2d(lo, lo), Eigen::Vector2d(hi, lo),
                                   Eigen::Vector2d(lo, hi), Eigen::Vector2d(hi, hi)}) {
    if (!insideForBilinear(source_level_image, centre + M_src_tpl * o)) return false;
  }
  // Bilinear sampling along template rows: positions advance by the first column of M.
  const float step_x = static_cast<float>(M_src_tpl(0, 0));
  const float step_y = static_cast<float>(M_src_tpl(1, 0));
  const int x_last = source_level_image.cols - 2, y_last = source_level_image.rows - 2;
  const uint8_t* base = source_level_image.ptr<uint8_t>();
  const size_t stride = source_level_image.step[0];
  for (int r = 0; r < kPaddedSize; ++r) {
    const Eigen::Vector2d start = centre + M_src_tpl * Eigen::Vector2d(lo, r - kPaddedOffset);
    float x = static_cast<float>(start.x()), y = static_cast<float>(start.y());
    uint8_t* out_row = out->padded.data() + r * kPaddedSize;
    for (int c = 0; c < kPaddedSize; ++c, x += step_x, y += step_y) {
      // The hull check keeps x, y in [0, cols-1] x [0, rows-1]; the clamp of the cell
      // guards the last column / row against rounding.
      const int x0 = std::min(static_cast<int>(x), x_last);
      const int y0 = std::min(static_cast<int>(y), y_last);
      const float fx = x - x0, fy = y - y0;
      const uint8_t* p = base + y0 * stride + x0;
      const float top = p[0] + fx * (p[1] - p[0]);
      const float bottom = p[stride] + fx * (p[stride + 1] - p[stride]);
      out_row[c] = static_cast<uint8_t>(top + fy * (bottom - top) + kRoundHalf);
    }
  }
  copyInner(out);
  finishPatch(out);
  return true;
}

bool extractPatch(const cv::Mat& level_image, cv::Point2i centre, Patch* out) {
  assert(level_image.type() == CV_8UC1);
  const int x0 = centre.x - kPaddedOffset, y0 = centre.y - kPaddedOffset;
  if (x0 < 0 || y0 < 0 || x0 + kPaddedSize > level_image.cols ||
      y0 + kPaddedSize > level_image.rows) {
    return false;
  }
  for (int r = 0; r < kPaddedSize; ++r) {
    const uint8_t* row = level_image.ptr<uint8_t>(y0 + r) + x0;
    std::copy(row, row + kPaddedSize, out->padded.data() + r * kPaddedSize);
  }
  copyInner(out);
  finishPatch(out);
  return true;
}

int zmssdAt(const Patch& patch, const cv::Mat& image, cv::Point2i centre) {
  assert(image.type() == CV_8UC1 && patchInImage(image, centre));
  const uint8_t* __restrict tpl = patch.pixels.data();
  const uint8_t* row = image.ptr<uint8_t>(centre.y - kPatchCentre) + (centre.x - kPatchCentre);
  const size_t stride = image.step[0];
  int sum_d = 0, sum_dd = 0;
  for (int r = 0; r < kPatchSize; ++r, row += stride, tpl += kPatchSize) {
    for (int c = 0; c < kPatchSize; ++c) {
      const int d = tpl[c] - row[c];
      sum_d += d;
      sum_dd += d * d;
    }
  }
  // sum_d^2 >= 0, so integer division is the floor.
  return sum_dd - (sum_d * sum_d) / kPatchArea;
}

int zmssdAtSubpixel(const Patch& patch, const cv::Mat& image, const Eigen::Vector2d& centre) {
  assert(image.type() == CV_8UC1);
  // Template offset o samples the image at centre + o; its top-left pixel at (x0, y0).
  const double left = centre.x() - kPatchCentre, top = centre.y() - kPatchCentre;
  if (!(left >= 0.0 && top >= 0.0 && left + kPatchSize < image.cols && top + kPatchSize < image.rows)) return -1;
  const int x0 = static_cast<int>(left), y0 = static_cast<int>(top);
  const int fx = static_cast<int>(std::lround((left - x0) * 256.0));
  const int fy = static_cast<int>(std::lround((top - y0) * 256.0));
  const int w00 = (256 - fx) * (256 - fy), w01 = fx * (256 - fy), w10 = (256 - fx) * fy, w11 = fx * fy;
  const size_t stride = image.step[0];
  const uint8_t* tpl = patch.pixels.data();
  int64_t sum_d = 0, sum_dd = 0;  // in 1/256 grey levels
  for (int r = 0; r < kPatchSize; ++r, tpl += kPatchSize) {
    const uint8_t* a = image.ptr<uint8_t>(y0 + r) + x0;
    const uint8_t* b = a + stride;
    for (int c = 0; c < kPatchSize; ++c) {
      const int sampled = (w00 * a[c] + w01 * a[c + 1] + w10 * b[c] + w11 * b[c + 1] + 128) >> 8;
      const int64_t d = tpl[c] * 256 - sampled;
      sum_d += d;
      sum_dd += d * d;
    }
  }
  return static_cast<int>((sum_dd - sum_d * sum_d / kPatchArea + 32768) >> 16);
}

std::optional<cv::Point2i> searchPatch(const Patch& patch, const cv::Mat& level_image,
                                       const LevelCorners& corners,
                                       const Eigen::Vector2d& predicted_level, int radius,
                                       int max_zmssd, int* best_score) {
  assert(corners.rows() == level_image.rows);
  const double px = predicted_level.x(), py = predicted_level.y();
  const double radius_sq = static_cast<double>(radius) * radius;
  const int y_begin = std::max(0, static_cast<int>(std::ceil(py - radius)));
  const int y_end = std::min(corners.rows() - 1, static_cast<int>(std::floor(py + radius)));
  const int x_min = static_cast<int>(std::ceil(px - radius));
  const int x_max = static_cast<int>(std::floor(px + radius));
  int best = INT_MAX;
  std::optional<cv::Point2i> best_position;
  const auto row_begin = corners.all.begin();
  for (int y = y_begin; y <= y_end; ++y) {
    const double dy = y - py;
    auto it = std::lower_bound(row_begin + corners.row_start[y],
                               row_begin + corners.row_start[y + 1], x_min,
                               [](const cv::Point2i& p, int x) { return p.x < x; });
    const auto end = row_begin + corners.row_start[y + 1];
    for (; it != end && it->x <= x_max; ++it) {
      const double dx = it->x - px;
      if (dx * dx + dy * dy > radius_sq || !patchInImage(level_image, *it)) continue;
      const int score = zmssdAt(patch, level_image, *it);
      if (score < best) {
        best = score;
        best_position = *it;
      }
    }
  }
  if (best_score) *best_score = best_position && best < max_zmssd ? best : INT_MAX;
  if (best >= max_zmssd) return std::nullopt;
  return best_position;
}

std::optional<cv::Point2i> bestMatchAmong(const Patch& patch, const cv::Mat& level_image,
                                          const std::vector<cv::Point2i>& candidates,
                                          int max_zmssd, int* best_score) {
  int best = INT_MAX;
  std::optional<cv::Point2i> best_position;
  for (const cv::Point2i& p : candidates) {
    if (!patchInImage(level_image, p)) continue;
    const int score = zmssdAt(patch, level_image, p);
    if (score < best) {
      best = score;
      best_position = p;
    }
  }
  if (best_score) *best_score = best < max_zmssd ? best : INT_MAX;
  if (best >= max_zmssd) return std::nullopt;
  return best_position;
}

bool refineSubpixel(const Patch& patch, const cv::Mat& level_image,
                    Eigen::Vector2d* position_level, const SubpixelOptions& options) {
  assert(level_image.type() == CV_8UC1);
  // Template Jacobian J = [dT/dx, dT/dy, 1] (central differences on the padded template)
  // and the constant Gauss-Newton matrix H = sum J J^T of the inverse-compositional method.
  float grad_x[kPatchArea], grad_y[kPatchArea], tpl[kPatchArea];
  double gxx = 0, gxy = 0, gyy = 0, gx1 = 0, gy1 = 0;
  for (int r = 0; r < kPatchSize; ++r) {
    const uint8_t* p = patch.padded.data() + (r + 1) * kPaddedSize + 1;
    for (int c = 0; c < kPatchSize; ++c) {
      const int i = r * kPatchSize + c;
      const float gx = 0.5f * (p[c + 1] - p[c - 1]);
      const float gy = 0.5f * (p[c + kPaddedSize] - p[c - kPaddedSize]);
      grad_x[i] = gx;
      grad_y[i] = gy;
      tpl[i] = p[c];
      gxx += gx * gx;
      gxy += gx * gy;
      gyy += gy * gy;
      gx1 += gx;
      gy1 += gy;
    }
  }
  Eigen::Matrix3d H;
  H << gxx, gxy, gx1, gxy, gyy, gy1, gx1, gy1, kPatchArea;
  // The bias absorbs the mean gradient: the texture is what remains (Schur complement).
  Eigen::Matrix2d S = H.topLeftCorner<2, 2>() - H.topRightCorner<2, 1>() *
                                                    H.bottomLeftCorner<1, 2>() / kPatchArea;
  const double half_trace = 0.5 * (S(0, 0) + S(1, 1));
  const double half_diff = 0.5 * (S(0, 0) - S(1, 1));
  const double min_eigenvalue = half_trace - std::sqrt(half_diff * half_diff + S(0, 1) * S(0, 1));
  if (!(min_eigenvalue >= kMinGradientEnergy)) return false;
  const Eigen::Matrix3d H_inv = H.inverse();

  const Eigen::Vector2d start = *position_level;
  Eigen::Vector2d p = start;
  const size_t stride = level_image.step[0];
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    const int x0 = static_cast<int>(std::floor(p.x()));
    const int y0 = static_cast<int>(std::floor(p.y()));
    // Samples at p + o, o in -4..+3, read pixels x0-4 .. x0+4 and y0-4 .. y0+4.
    if (x0 < kPatchCentre || y0 < kPatchCentre ||
        x0 + kPatchSize - kPatchCentre >= level_image.cols ||
        y0 + kPatchSize - kPatchCentre >= level_image.rows) {
      return false;
    }
    const float fx = static_cast<float>(p.x() - x0), fy = static_cast<float>(p.y() - y0);
    const float w00 = (1 - fx) * (1 - fy), w01 = fx * (1 - fy);
    const float w10 = (1 - fx) * fy, w11 = fx * fy;
    const uint8_t* row = level_image.ptr<uint8_t>(y0 - kPatchCentre) + (x0 - kPatchCentre);
    float sum_ex = 0, sum_ey = 0, sum_e = 0;
    for (int r = 0; r < kPatchSize; ++r, row += stride) {
      const uint8_t* next = row + stride;
      for (int c = 0; c < kPatchSize; ++c) {
        const int i = r * kPatchSize + c;
        const float value =
            w00 * row[c] + w01 * row[c + 1] + w10 * next[c] + w11 * next[c + 1];
        const float e = value - tpl[i];
        sum_ex += e * grad_x[i];
        sum_ey += e * grad_y[i];
        sum_e += e;
      }
    }
    const Eigen::Vector3d delta = H_inv * Eigen::Vector3d(sum_ex, sum_ey, sum_e);
    // Inverse composition: T(o + delta) ~ I(p + o) means the patch is at p - delta.
    p -= delta.head<2>();
    if ((p - start).norm() > options.max_shift) return false;
    if (delta.head<2>().norm() < options.converged_step) {
      *position_level = p;
      return true;
    }
  }
  return false;
}

}  // namespace rgbdslam
