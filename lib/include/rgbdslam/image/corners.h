#pragma once
// FAST corners per pyramid level. Why: PTAM searches a map point's patch only at FAST corners
// near its predicted position (cheap, and corners are where a patch localises well), and
// keyframes take their new map-point candidates from the score-based local maxima ranked by
// the Shi-Tomasi score.
//
// Call order: per frame and level, detectFastCorners() (all corners + row index) -- enough
// for tracking; for a keyframe also computeMaxima() (FAST scores + non-maximum suppression).
// detectCorners() does both; detectPyramidCorners() runs a whole pyramid. Pass the same
// LevelCorners every frame: its vectors keep their capacity, so there is no allocation once
// the corner counts are stable.
//
// Frames and units: integer pixel positions cv::Point2i(x = column, y = row) of the level
// the corners were detected in (level pixels; see pyramid.h for converting levels).
// Thresholds and scores are grey-level differences [0..255].
#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "rgbdslam/image/pyramid.h"

namespace rgbdslam {

struct CornerOptions {
  // FAST-10 threshold per level [grey levels]: a corner has 10 contiguous pixels of the
  // 16 on the radius-3 circle all brighter, or all darker, than the centre by more than the
  // threshold. These are PTAM's values (FAST-10 with 10, 15, 15, 10): level 0 low for many
  // fine corners; levels 1-2 higher because 2x2 averaging removes noise but keeps contrast,
  // so the same threshold would clutter them; level 3 (80x60) low again so that coarse
  // tracking of fast motion has enough corners.
  std::array<int, kMaxLevels> fast_thresholds{10, 15, 15, 10};
  // Corners closer than this to the image edge are dropped [level px]. An 8x8 patch centred
  // on a corner spans offsets -4..+3 (patch.h), and one more pixel lets sub-pixel refinement
  // and the warped template's gradient margin stay inside the image.
  int border = 5;
};

// Shi-Tomasi window half size used by the map initialiser and keyframes [px]: a 7x7 window
// as in PTAM.
constexpr int kShiTomasiHalfWindow = 3;

struct LevelCorners {
  // FAST corners without non-maximum suppression, sorted by row (y) then column (x).
  std::vector<cv::Point2i> all;
  // row_start[y] = index in 'all' of the first corner with row >= y; size rows + 1, so the
  // corners of row y are all[row_start[y] .. row_start[y + 1]).
  std::vector<int> row_start;
  // FAST score of each corner in 'all' (same order): the largest threshold at which it is
  // still a FAST-10 corner [grey levels]. Filled by computeMaxima(), empty otherwise.
  std::vector<int> scores;
  // Corners whose score beats their 8-neighbourhood among 'all' (ties: the first in
  // raster order wins), in the order of 'all'. Filled by computeMaxima(), empty otherwise.
  std::vector<cv::Point2i> maxima;

  int rows() const { return static_cast<int>(row_start.size()) - 1; }
};

// FAST-10 corners of a CV_8UC1 level image into out->all and out->row_start; clears
// out->scores and out->maxima.
void detectFastCorners(const cv::Mat& level_image, int threshold, int border,
                       LevelCorners* out);
// FAST scores of corners->all and the score-based non-maximum suppression into
// corners->maxima. level_image must be the image the corners were detected in.
void computeMaxima(const cv::Mat& level_image, LevelCorners* corners);
// detectFastCorners() then computeMaxima().
void detectCorners(const cv::Mat& level_image, int threshold, int border, LevelCorners* out);
// All levels of a pyramid with options.fast_thresholds; out is resized to the level count.
// with_maxima: also run computeMaxima() (needed for keyframes only).
void detectPyramidCorners(const ImagePyramid& pyramid, const CornerOptions& options,
                          bool with_maxima, std::vector<LevelCorners>* out);

// How far a lossy codec's error (JPEG at quality 30-45: about 3 grey levels rms, PSNR 38-39
// dB on corridor frames) can move a FAST score: corners of an image to be sent lossy, and of
// one received so, are taken this far below the thresholds, so that a corner of the
// original is still found in the decoded image (the mapper's re-finding and epipolar search
// match only at corners; session 19, docs/open_work.md).
constexpr int kLossyCornerMargin = 4;  // [grey levels]
// options.fast_thresholds lowered by 'margin' (to 1 at least) [grey levels].
CornerOptions lossyCornerOptions(CornerOptions options, int margin = kLossyCornerMargin);

// The step x step blocks of a level-0 image of 'size' (block (bu, bv) covers columns
// bu * step .. bu * step + step - 1, rows likewise) holding a pixel within 2^level + 1 px
// (in both axes) of a corner of 'corners' at its level-0 position: 255 there, 0 elsewhere;
// ceil(width / step) x ceil(height / step), CV_8UC1. For the keyframe depth on the link:
// the mapper reads depth only where it matches a patch, and it matches at FAST corners
// (re-finding, epipolar search; the ORB keypoints of loop closure are FAST corners too), at
// a position known to about a pixel of the corner's level, hence the margin.
cv::Mat cornerBlockMask(const std::vector<LevelCorners>& corners, int step, cv::Size size);

// FAST-10 score of pixel p (the largest threshold at which p is a corner; 0 or below if it
// is not a corner at threshold 0) [grey levels]. p must be >= 3 px from the image edge.
int fastScore(const cv::Mat& image, cv::Point2i p);

// Shi-Tomasi score: the smaller eigenvalue of the structure tensor averaged over the
// (2 half_window + 1)^2 window centred on p, with central-difference gradients
// [(grey levels / px)^2]. Returns 0 when the window and its gradient margin leave the image.
float shiTomasiScore(const cv::Mat& image, cv::Point2i p, int half_window = kShiTomasiHalfWindow);

// The image noise's standard deviation [grey levels], by Immerkaer's estimator ("Fast noise
// variance estimation", CVIU 1996): the mean absolute response to the difference of two
// Laplacians, which cancels intensity ramps, over every interior pixel of every other row.
// Texture and edges add to it, so on average it bounds the noise from above (not where
// pixels clip at 0 or 255, which hides noise). 0 for images under 3x3.
double imageNoiseSigma(const cv::Mat& image);

// The scale of the Shi-Tomasi score that image noise of 'sigma' alone gives: central-
// difference gradients of independent pixel noise have variance sigma^2 / 2 in each
// direction, the mean of the structure tensor's diagonal. The score, its smaller
// eigenvalue, averages less: about 0.8 times this (test_corners).
inline double noiseShiTomasiScore(double sigma) { return 0.5 * sigma * sigma; }

}  // namespace rgbdslam
