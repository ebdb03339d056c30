#pragma once
// Image pyramid of the PTAM tracker. Why: corners are detected and patches searched at the
// pyramid level whose scale matches a map point's apparent size, and coarse levels make
// large motions cheap to search. Level l+1 is the 2x2 box average of level l (half size,
// odd last rows/columns dropped), as in PTAM.
//
// Call order, once per frame: buildPyramid() -> detectCorners() on each level (corners.h)
// -> patch search (patch.h) -> makeSmallBlurryImage() (small_blurry_image.h).
//
// Frames and units: pixel coordinates (u, v) [px of the level] have (0, 0) at the centre of
// the top-left pixel (as camera/pinhole_camera.h), u to the right, v down. A level-l pixel
// covers 2^l x 2^l level-0 pixels, so the centres relate by
//   u_l = (u_0 + 0.5) / 2^l - 0.5        u_0 = (u_l + 0.5) * 2^l - 0.5.
#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <vector>

namespace rgbdslam {

constexpr int kMaxLevels = 4;  // levels 0..3: 640x480 down to 80x60

struct ImagePyramid {
  // levels[0] is the input grey image (CV_8UC1, sharing its data, no copy); levels[l] for
  // l >= 1 are owned CV_8UC1 images of size floor(size_{l-1} / 2).
  std::vector<cv::Mat> levels;

  int numLevels() const { return static_cast<int>(levels.size()); }
};

// Builds num_levels levels (1..kMaxLevels) from a CV_8UC1 image. Pixel (x, y) of level l+1
// is (a + b + c + d + 2) / 4 (integer, rounded half up) of the 2x2 block at (2x, 2y) of
// level l.
ImagePyramid buildPyramid(const cv::Mat& grey, int num_levels = kMaxLevels);
// The same, reusing out's level buffers (no allocation once sizes are stable). The buffers
// are written in place: move a pyramid away (or clone it) before keeping it, e.g. in a
// keyframe, and do not share its levels with another cv::Mat.
void buildPyramid(const cv::Mat& grey, int num_levels, ImagePyramid* out);

// One level of 2x2 averaging: dst = half-size box average of src (dst is (re)allocated).
void halfSample(const cv::Mat& src, cv::Mat* dst);

// Size of one pixel of 'level' in level-0 pixels: 2^level.
inline double levelScale(int level) { return static_cast<double>(1 << level); }

// Level-0 pixel -> pixel of 'level' (pixel-centre convention above).
inline Eigen::Vector2d levelFromZero(const Eigen::Vector2d& uv_0, int level) {
  const double s = levelScale(level);
  return Eigen::Vector2d((uv_0.x() + 0.5) / s - 0.5, (uv_0.y() + 0.5) / s - 0.5);
}
// Pixel of 'level' -> level-0 pixel.
inline Eigen::Vector2d zeroFromLevel(const Eigen::Vector2d& uv_l, int level) {
  const double s = levelScale(level);
  return Eigen::Vector2d((uv_l.x() + 0.5) * s - 0.5, (uv_l.y() + 0.5) * s - 0.5);
}

}  // namespace rgbdslam
