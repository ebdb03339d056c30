#pragma once
// 8x8 template patches, PTAM style. Why: the tracker finds each map point in the current
// frame by warping the point's appearance in its source keyframe into the current view (an
// affine warp from the projected neighbourhood), searching for it by zero-mean SSD among the
// FAST corners near the predicted position, and refining the best match to sub-pixel
// accuracy. The same patches serve the mapper's epipolar search (bestMatchAmong()).
//
// Call order, per map point and frame:
//   level = chooseSearchLevel(A_cur_src, source_level, num_levels)
//   warpPatch(kf.levels[source_level], source_level, uv_src_0, A_cur_src, level, &patch)
//   best = searchPatch(patch, cur.levels[level], cur_corners[level], predicted_level, ...)
//   refineSubpixel(patch, cur.levels[level], &position_level)  // starts at *best
//   uv_cur_0 = zeroFromLevel(position_level, level)
//
// Frames and units: positions are pixel coordinates of one pyramid level, (0, 0) at the
// centre of the top-left pixel (pyramid.h). A patch has a centre: patch pixel (row r,
// column c), r, c in 0..7, holds the template at offset (c - 4, r - 4) [px of the search
// level] from the centre, so an integer centre (x, y) covers image columns x-4..x+3 and rows
// y-4..y+3. A_cur_src maps a small offset [level-0 px] around the point's pixel in its
// source keyframe to the corresponding offset [level-0 px] in the current image.
// Grey values are 0..255; ZMSSD values are in grey levels^2 summed over the 64 pixels.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "rgbdslam/image/corners.h"

namespace rgbdslam {

constexpr int kPatchSize = 8;                            // template side [px]
constexpr int kPatchCentre = kPatchSize / 2;             // index of the centre pixel
constexpr int kPatchArea = kPatchSize * kPatchSize;      // 64 pixels
constexpr int kPaddedSize = kPatchSize + 2;              // template with a 1-px margin
constexpr int kPaddedArea = kPaddedSize * kPaddedSize;   // 100 pixels
// PTAM's rule: go up a search level while the area magnification from source-level pixels
// to search-level pixels, det(A) * 4^(source_level - level), exceeds this.
constexpr double kLevelUpDeterminant = 3.0;

struct Patch {
  // The template, row-major, pixel (r, c) at offset (c - 4, r - 4) from the centre.
  alignas(16) std::array<uint8_t, kPatchArea> pixels{};
  // The template with one more pixel on each side (offsets -5..+4), row-major; its inner
  // 8x8 equals 'pixels'. Gives the template gradients for sub-pixel refinement.
  std::array<uint8_t, kPaddedArea> padded{};
  int sum = 0;     // sum of 'pixels' [grey levels]
  int sum_sq = 0;  // sum of squares of 'pixels' [grey levels^2]
};

// Search level in the current frame for a point seen at source_level of its keyframe
// (PTAM's rule): start at level 0 with det = det(A_cur_src) * 4^source_level (the area
// magnification from source-level pixels to current level-0 pixels) and go up one level,
// dividing det by 4, while det > kLevelUpDeterminant and the level is below num_levels - 1.
// Returns -1 when det(A_cur_src) <= 0 (a degenerate or mirrored warp).
int chooseSearchLevel(const Eigen::Matrix2d& A_cur_src, int source_level, int num_levels);

// Fills 'out' by bilinear sampling of the source keyframe's level image: the template
// offset o [search-level px] samples the source level at
//   levelFromZero(source_uv_level0, source_level) + A_cur_src^-1 o * 2^(search - source).
// Pixel values are rounded to the nearest grey level. Returns false (out unspecified) if the
// sampled region (including the 1-px margin) leaves the image or A_cur_src is singular.
bool warpPatch(const cv::Mat& source_level_image, int source_level,
               const Eigen::Vector2d& source_uv_level0, const Eigen::Matrix2d& A_cur_src,
               int search_level, Patch* out);
// The unwarped patch around an integer centre (A = identity, same level). False if it
// leaves the image.
bool extractPatch(const cv::Mat& level_image, cv::Point2i centre, Patch* out);

// Zero-mean SSD between the patch and the image patch with the same centre:
//   sum d^2 - (sum d)^2 / 64, d = template - image, in integers (floor division).
// Invariant to adding a constant to the image (while nothing saturates). The caller keeps
// columns centre.x-4..centre.x+3 and rows centre.y-4..centre.y+3 inside the image.
int zmssdAt(const Patch& patch, const cv::Mat& image, cv::Point2i centre);
// The same at a sub-pixel centre [px of the image's level], the image sampled bilinearly
// (in 1/256 grey steps, rounded back to grey levels^2). -1 if the patch (and the one pixel
// the interpolation reads beyond it) leaves the image.
int zmssdAtSubpixel(const Patch& patch, const cv::Mat& image, const Eigen::Vector2d& centre);
// True if a patch centred at 'centre' lies inside the image.
inline bool patchInImage(const cv::Mat& image, cv::Point2i centre) {
  return centre.x >= kPatchCentre && centre.y >= kPatchCentre &&
         centre.x + kPatchSize - kPatchCentre <= image.cols &&
         centre.y + kPatchSize - kPatchCentre <= image.rows;
}

// The corner of 'corners' (detected in level_image) within 'radius' [px] (Euclidean) of
// predicted_level whose ZMSSD is smallest and below max_zmssd; nullopt if none. best_score
// (optional) receives that ZMSSD (INT_MAX when there is no match).
std::optional<cv::Point2i> searchPatch(const Patch& patch, const cv::Mat& level_image,
                                       const LevelCorners& corners,
                                       const Eigen::Vector2d& predicted_level, int radius,
                                       int max_zmssd, int* best_score = nullptr);
// The candidate position (patch centres; those leaving the image are skipped) with the
// smallest ZMSSD below max_zmssd; nullopt if none. For epipolar search and relocalisation.
std::optional<cv::Point2i> bestMatchAmong(const Patch& patch, const cv::Mat& level_image,
                                          const std::vector<cv::Point2i>& candidates,
                                          int max_zmssd, int* best_score = nullptr);

struct SubpixelOptions {
  int max_iterations = 10;       // Gauss-Newton iterations at most
  double converged_step = 0.03;  // converged when an update is shorter than this [px]
  // Diverged when the position moves further than this from its start [px]: a correct
  // integer match is within about 0.5 px, and beyond 1.5 px the match was a different
  // corner.
  double max_shift = 1.5;
};

// Inverse-compositional, translation-only alignment of the patch to the image with a
// brightness bias: finds p minimising sum_o (I(p + o) - T(o) - b)^2 over the 64 template
// offsets o, with bilinear sampling of I. *position_level is the start (e.g. the integer
// match of searchPatch) and receives the result [px of the level]. Returns true when an
// update became shorter than converged_step; false (position unchanged) if it diverged, left
// the image, did not converge in max_iterations, or the template has no texture.
bool refineSubpixel(const Patch& patch, const cv::Mat& level_image,
                    Eigen::Vector2d* position_level, const SubpixelOptions& options = {});

}  // namespace rgbdslam
