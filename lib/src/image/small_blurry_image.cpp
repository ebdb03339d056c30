#include "rgbdslam/image/small_blurry_image.h"

#include <Eigen/Dense>
#include <cassert>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace rgbdslam {
namespace {

constexpr double kCentralDiff = 0.5;  // central difference: (I(x+1) - I(x-1)) / 2
constexpr double kBlurHalfWidthSigmas = 3.0;  // Gaussian kernel truncated at 3 sigma
// Pixels of 'from' on the outermost ring are not used: their gradients are one-sided [px].
constexpr int kAlignBorder = 1;
// Residuals are weighted by (support_from * support_to)^(2^kSupportSquarings) = ^16: about
// 1 further than 2 sigma from the edge, below 0.02 within 2 px of it. Near the edge the
// blur kernel is truncated, so the SBI there depends on where the frame cuts the scene and
// would pull the alignment towards the identity (measured: up to 0.5 deg of rotation bias
// unweighted, 0.2 deg weighted, for rotations up to 8 deg).
constexpr int kSupportSquarings = 4;
// Iterations stop early once an update is below both of these [rad], [SBI px]: far below
// the accuracy of the estimate (ESM converges in 3-4 iterations).
constexpr double kConvergedAngle = 1e-4;
constexpr double kConvergedShift = 1e-3;
constexpr double kMinWeightSum = 4.0;  // fewer effective pixels than parameters: give up
// Grid of SBI pixels for rotationFromSe2: offsets from the centre of -1/4, 0, +1/4 of the
// SBI size in each axis.
constexpr double kGridFraction = 0.25;
constexpr int kGridSide = 3;

Eigen::Matrix2d rotation2d(double theta) {
  Eigen::Matrix2d R;
  R << std::cos(theta), -std::sin(theta), std::sin(theta), std::cos(theta);
  return R;
}

// Normal equations of the weighted ESM residuals at one warp estimate.
struct EsmSystem {
  Eigen::Matrix4d JtWJ = Eigen::Matrix4d::Zero();  // over (theta, tx, ty, bias)
  Eigen::Vector4d JtWr = Eigen::Vector4d::Zero();
  double weighted_sq = 0;  // sum w r^2 [grey levels^2]
  double weight_sum = 0;   // sum w
};

// Accumulates the residuals r = to(W(x)) - from(x) - bias over the pixels x of 'from' whose
// warp lands inside 'to'. W is composed with the update on the right (W o W_delta), so the
// Jacobian is taken in 'from' coordinates: d W_delta(x) / d (theta, tx, ty) =
// [-(y - c_y), 1, 0; x - c_x, 0, 1], times the image gradient in 'from' coordinates, for
// which ESM uses the mean of grad(to o W) = R^T grad_to(W(x)) and grad_from(x).
EsmSystem accumulateEsm(const SmallBlurryImage& from, const SmallBlurryImage& to,
                        const Se2& warp, double bias) {
  const double cs = std::cos(warp.theta), sn = std::sin(warp.theta);
  const double c_x = 0.5 * (from.image.cols - 1), c_y = 0.5 * (from.image.rows - 1);
  const double x_limit = to.image.cols - 1, y_limit = to.image.rows - 1;
  const size_t to_stride = to.image.step[0] / sizeof(float);
  double h[10] = {0};  // upper triangle of J^T W J, row-major
  double g[4] = {0};
  double weighted_sq = 0, weight_sum = 0;
  for (int y = kAlignBorder; y < from.image.rows - kAlignBorder; ++y) {
    const float* from_value = from.image.ptr<float>(y);
    const float* from_gx = from.grad_x.ptr<float>(y);
    const float* from_gy = from.grad_y.ptr<float>(y);
    const float* from_support = from.support.ptr<float>(y);
    const double oy = y - c_y;
    for (int x = kAlignBorder; x < from.image.cols - kAlignBorder; ++x) {
      const double ox = x - c_x;
      const double wx = cs * ox - sn * oy + c_x + warp.tx;
      const double wy = sn * ox + cs * oy + c_y + warp.ty;
      if (!(wx >= 0 && wy >= 0 && wx < x_limit && wy < y_limit)) continue;
      // One set of bilinear weights for the four images of 'to'.
      const int x0 = static_cast<int>(wx), y0 = static_cast<int>(wy);
      const float fx = static_cast<float>(wx - x0), fy = static_cast<float>(wy - y0);
      const float w00 = (1 - fx) * (1 - fy), w01 = fx * (1 - fy), w10 = (1 - fx) * fy,
                  w11 = fx * fy;
      const size_t i = y0 * to_stride + x0;
      auto sample = [&](const cv::Mat& image) {
        const float* p = image.ptr<float>() + i;
        return w00 * p[0] + w01 * p[1] + w10 * p[to_stride] + w11 * p[to_stride + 1];
      };
      double weight = from_support[x] * sample(to.support);
      for (int k = 0; k < kSupportSquarings; ++k) weight *= weight;
      const double r = sample(to.image) - from_value[x] - bias;
      // ESM gradient in 'from' coordinates: (R^T grad_to + grad_from) / 2.
      const double tgx = sample(to.grad_x), tgy = sample(to.grad_y);
      const double gx = 0.5 * (cs * tgx + sn * tgy + from_gx[x]);
      const double gy = 0.5 * (-sn * tgx + cs * tgy + from_gy[x]);
      const double J[4] = {-gx * oy + gy * ox, gx, gy, -1.0};
      int k = 0;
      for (int a = 0; a < 4; ++a) {
        const double wJa = weight * J[a];
        g[a] += wJa * r;
        for (int b = a; b < 4; ++b) h[k++] += wJa * J[b];
      }
      weighted_sq += weight * r * r;
      weight_sum += weight;
    }
  }
  EsmSystem system;
  int k = 0;
  for (int a = 0; a < 4; ++a) {
    system.JtWr(a) = g[a];
    for (int b = a; b < 4; ++b, ++k) system.JtWJ(a, b) = system.JtWJ(b, a) = h[k];
  }
  system.weighted_sq = weighted_sq;
  system.weight_sum = weight_sum;
  return system;
}

// For each output index i in [0, n), the sum of the kernel taps that fall inside [0, n):
// the 1-D normaliser of a zero-padded convolution.
void kernelSupport(const cv::Mat& kernel, int n, std::vector<float>* support) {
  const int half = kernel.rows / 2;
  support->assign(n, 0.0f);
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < kernel.rows; ++k) {
      const int source = i + k - half;
      if (source >= 0 && source < n) (*support)[i] += kernel.at<float>(k);
    }
  }
}

// The SBI's Gaussian (kSbiBlurSigma), 1-D.
cv::Mat blurKernel() {
  const int ksize = 2 * static_cast<int>(std::ceil(kBlurHalfWidthSigmas * kSbiBlurSigma)) + 1;
  return cv::getGaussianKernel(ksize, kSbiBlurSigma, CV_32F);
}

// The blurred mask of valid pixels of an image of this size (separable: the product of
// 1-D sums).
void blurSupport(const cv::Mat& kernel, cv::Size size, cv::Mat* support) {
  std::vector<float> support_x, support_y;
  kernelSupport(kernel, size.width, &support_x);
  kernelSupport(kernel, size.height, &support_y);
  support->create(size, CV_32FC1);
  for (int y = 0; y < size.height; ++y) {
    float* weight = support->ptr<float>(y);
    for (int x = 0; x < size.width; ++x) weight[x] = support_y[y] * support_x[x];
  }
}

// d image / dx and / dy by central differences.
void gradients(SmallBlurryImage* sbi) {
  cv::Sobel(sbi->image, sbi->grad_x, CV_32F, 1, 0, 1, kCentralDiff, 0, cv::BORDER_REPLICATE);
  cv::Sobel(sbi->image, sbi->grad_y, CV_32F, 0, 1, 1, kCentralDiff, 0, cv::BORDER_REPLICATE);
}

// Gaussian blur by normalised convolution: zero padding, divided by the blurred mask of
// valid pixels (written to *support). Replicated or mirrored borders would invent structure
// fixed to the image frame.
void blurNormalised(cv::Mat* image, cv::Mat* support) {
  const cv::Mat kernel = blurKernel();
  cv::sepFilter2D(*image, *image, CV_32F, kernel, kernel, cv::Point(-1, -1), 0,
                  cv::BORDER_CONSTANT);
  blurSupport(kernel, image->size(), support);
  for (int y = 0; y < image->rows; ++y) {
    float* value = image->ptr<float>(y);
    const float* weight = support->ptr<float>(y);
    for (int x = 0; x < image->cols; ++x) {
      value[x] /= weight[x];
    }
  }
}

}  // namespace

void makeSmallBlurryImage(const ImagePyramid& pyramid, SmallBlurryImage* out) {
  assert(pyramid.numLevels() >= 1);
  cv::Mat small = pyramid.levels.back();
  for (int level = pyramid.numLevels() - 1; level < kSbiLevel; ++level) {
    cv::Mat half;
    halfSample(small, &half);
    small = half;
  }
  small.convertTo(out->image, CV_32F);
  blurNormalised(&out->image, &out->support);
  out->image -= cv::mean(out->image)[0];
  gradients(out);
  out->scale = 1.0 / (1 << kSbiLevel);
}

void compactSmallBlurryImage(SmallBlurryImage* sbi) {
  sbi->grad_x.release();
  sbi->grad_y.release();
  sbi->support.release();
}

void restoreSmallBlurryImage(SmallBlurryImage* sbi) {
  if (sbi->complete() || sbi->image.empty()) return;
  blurSupport(blurKernel(), sbi->image.size(), &sbi->support);
  gradients(sbi);
}

SmallBlurryImage makeSmallBlurryImage(const ImagePyramid& pyramid) {
  SmallBlurryImage sbi;
  makeSmallBlurryImage(pyramid, &sbi);
  return sbi;
}

SmallBlurryImage halveSmallBlurryImage(const SmallBlurryImage& sbi) {
  SmallBlurryImage half;
  half.scale = 0.5 * sbi.scale;
  const cv::Size size(sbi.image.cols / 2, sbi.image.rows / 2);
  if (size.area() == 0) return half;
  cv::Mat support = sbi.support;  // a compact SBI's follows from its size
  if (support.empty()) blurSupport(blurKernel(), sbi.image.size(), &support);
  const cv::Rect even(0, 0, 2 * size.width, 2 * size.height);
  // INTER_AREA at a factor of exactly 2 is the mean of each 2 x 2 block.
  cv::resize(sbi.image(even), half.image, size, 0, 0, cv::INTER_AREA);
  cv::resize(support(even), half.support, size, 0, 0, cv::INTER_AREA);
  gradients(&half);
  return half;
}

Se2 fullResolutionSe2(const Se2& half, cv::Size full) {
  // W_h(x_h) = R (x_h - c_h) + c_h + t_h and x = 2 x_h + 0.5 give W(x) = R (x - c) + c + t with
  // t = 2 (t_h - (d - R d)), d = (c - 0.5) / 2 - c_h: zero for even sizes.
  const Eigen::Vector2d c(0.5 * (full.width - 1), 0.5 * (full.height - 1));
  const Eigen::Vector2d c_h(0.5 * (full.width / 2 - 1), 0.5 * (full.height / 2 - 1));
  const Eigen::Vector2d d = 0.5 * (c.array() - 0.5).matrix() - c_h;
  const Eigen::Vector2d t = 2.0 * (Eigen::Vector2d(half.tx, half.ty) - (d - rotation2d(half.theta) * d));
  return Se2{half.theta, t.x(), t.y()};
}

double zmssd(const SmallBlurryImage& a, const SmallBlurryImage& b) {
  assert(a.image.size() == b.image.size());
  const double mean_difference = cv::mean(a.image)[0] - cv::mean(b.image)[0];
  double sum = 0;
  for (int y = 0; y < a.image.rows; ++y) {
    const float* row_a = a.image.ptr<float>(y);
    const float* row_b = b.image.ptr<float>(y);
    for (int x = 0; x < a.image.cols; ++x) {
      const double d = row_a[x] - row_b[x] - mean_difference;
      sum += d * d;
    }
  }
  return sum;
}

Se2 alignSmallBlurryImages(const SmallBlurryImage& from, const SmallBlurryImage& to,
                           int iterations, double* final_error, const Se2& start) {
  assert(from.image.size() == to.image.size());
  Se2 warp = start;
  double bias = 0;
  for (int iteration = 0; iteration < iterations; ++iteration) {
    const EsmSystem system = accumulateEsm(from, to, warp, bias);
    if (system.weight_sum < kMinWeightSum) break;
    const Eigen::LDLT<Eigen::Matrix4d> solver(system.JtWJ);
    if (solver.info() != Eigen::Success) break;
    const Eigen::Vector4d delta = solver.solve(-system.JtWr);
    // Compose on the right: W <- W o W_delta, i.e. theta += d_theta, t += R(theta) d_t.
    const Eigen::Vector2d t_delta = rotation2d(warp.theta) * delta.segment<2>(1);
    warp.theta += delta(0);
    warp.tx += t_delta.x();
    warp.ty += t_delta.y();
    bias += delta(3);
    if (std::abs(delta(0)) < kConvergedAngle && t_delta.norm() < kConvergedShift) break;
  }
  if (final_error) {
    const EsmSystem system = accumulateEsm(from, to, warp, bias);
    *final_error = system.weight_sum >= kMinWeightSum ? system.weighted_sq / system.weight_sum : INFINITY;
  }
  return warp;
}

SE3 rotationFromSe2(const Se2& se2, const PinholeCamera& full_res_camera, double sbi_scale) {
  // SBI geometry follows from the camera's image size.
  const double sbi_cols = full_res_camera.width * sbi_scale;
  const double sbi_rows = full_res_camera.height * sbi_scale;
  const Eigen::Vector2d c(0.5 * (sbi_cols - 1), 0.5 * (sbi_rows - 1));
  const Eigen::Matrix2d R2 = rotation2d(se2.theta);
  const Eigen::Vector2d t(se2.tx, se2.ty);
  auto bearing = [&](const Eigen::Vector2d& uv_sbi) {
    const Eigen::Vector2d uv_0 = (uv_sbi.array() + 0.5) / sbi_scale - 0.5;
    return full_res_camera.unproject(uv_0, 1.0).normalized().eval();
  };
  // Kabsch: R_new_old minimising sum_i |d_new_i - R d_old_i|^2.
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (int i = 0; i < kGridSide; ++i) {
    for (int j = 0; j < kGridSide; ++j) {
      const Eigen::Vector2d offset((j - kGridSide / 2) * kGridFraction * sbi_cols,
                                   (i - kGridSide / 2) * kGridFraction * sbi_rows);
      const Eigen::Vector2d from = c + offset;
      const Eigen::Vector2d to = R2 * offset + c + t;
      H += bearing(to) * bearing(from).transpose();
    }
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  const Eigen::Matrix3d R_new_old = svd.matrixU() * D * svd.matrixV().transpose();
  return SE3(Eigen::Matrix3d(R_new_old.transpose()), Vec3::Zero());
}

}  // namespace rgbdslam
