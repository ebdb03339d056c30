#include "rgbdslam/geometry/alignment.h"

#include <Eigen/SVD>
#include <algorithm>
#include <string>

namespace rgbdslam {
namespace {

// Spread below this (mean squared distance to the centroid, in squared input units) counts
// as "all points coincide". Relative to the larger spread of the two sets, plus an absolute
// floor for sets that are all zero.
constexpr double kRelativeDegenerateSpread = 1e-20;
constexpr double kAbsoluteDegenerateSpread = 1e-30;

Vec3 centroid(const std::vector<Vec3>& points) {
  Vec3 sum = Vec3::Zero();
  for (const Vec3& p : points) sum += p;
  return sum / static_cast<double>(points.size());
}

double meanSquaredSpread(const std::vector<Vec3>& points, const Vec3& mean) {
  double sum = 0.0;
  for (const Vec3& p : points) sum += (p - mean).squaredNorm();
  return sum / static_cast<double>(points.size());
}

}  // namespace

Expected<Sim3> alignPoints(const std::vector<Vec3>& source, const std::vector<Vec3>& target,
                           AlignmentKind kind) {
  if (source.size() != target.size()) {
    return Error{"alignPoints: " + std::to_string(source.size()) + " source points but " +
                 std::to_string(target.size()) + " target points"};
  }
  if (source.size() < 3) {
    return Error{"alignPoints: need at least 3 point pairs, got " + std::to_string(source.size())};
  }
  const double n = static_cast<double>(source.size());
  const Vec3 mean_source = centroid(source);
  const Vec3 mean_target = centroid(target);
  const double var_source = meanSquaredSpread(source, mean_source);
  const double var_target = meanSquaredSpread(target, mean_target);
  const double floor = std::max(kAbsoluteDegenerateSpread,
                                kRelativeDegenerateSpread * std::max(var_source, var_target));
  if (var_source <= floor || var_target <= floor) {
    return Error{"alignPoints: degenerate point set (all " +
                 std::string(var_source <= floor ? "source" : "target") + " points coincide)"};
  }

  // Cross-covariance Sigma = 1/n sum (y - mean_y)(x - mean_x)^T with x = source, y = target.
  Mat3 sigma = Mat3::Zero();
  for (size_t i = 0; i < source.size(); ++i) {
    sigma += (target[i] - mean_target) * (source[i] - mean_source).transpose();
  }
  sigma /= n;

  const Eigen::JacobiSVD<Mat3> svd(sigma, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Mat3& U = svd.matrixU();
  const Mat3& V = svd.matrixV();
  Vec3 reflection_fix = Vec3::Ones();
  if (U.determinant() * V.determinant() < 0.0) reflection_fix.z() = -1.0;

  Sim3 S_target_source;
  S_target_source.R = U * reflection_fix.asDiagonal() * V.transpose();
  if (kind == AlignmentKind::kSimilarity) {
    S_target_source.scale = svd.singularValues().dot(reflection_fix) / var_source;
    if (!(S_target_source.scale > 0.0)) {
      return Error{"alignPoints: degenerate point sets (no positive scale relates them)"};
    }
  }
  S_target_source.t = mean_target - S_target_source.scale * (S_target_source.R * mean_source);
  return S_target_source;
}

}  // namespace rgbdslam
