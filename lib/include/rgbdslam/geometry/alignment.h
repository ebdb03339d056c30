#pragma once
// Least-squares alignment of two corresponding 3-D point sets (Umeyama 1991), rigid (R, t)
// or with a scale (s, R, t). Used by trajectory evaluation to bring an estimated trajectory,
// expressed in its own world frame, into the ground-truth world frame before comparing.
//
// Frames: alignPoints(p_est, p_gt, ...) returns S_gt_est, which maps points in the estimate's
// world frame into the ground-truth world frame: p_gt ~= S_gt_est * p_est = s R p_est + t,
// minimising sum_i |p_gt_i - (s R p_est_i + t)|^2. R is a proper rotation (det = +1).
// Units: t in the ground truth's units (metres); s is dimensionless (1 for rigid).
#include <vector>

#include "rgbdslam/geometry/se3.h"
#include "rgbdslam/util/expected.h"

namespace rgbdslam {

enum class AlignmentKind {
  kRigid,       // s fixed to 1: for metric (RGB-D) trajectories
  kSimilarity,  // s estimated too: for monocular trajectories with unknown scale
};

// A similarity transform p_a = s * R * p_b + t.
struct Sim3 {
  double scale = 1.0;
  Mat3 R = Mat3::Identity();
  Vec3 t = Vec3::Zero();

  Vec3 operator*(const Vec3& p_b) const { return scale * (R * p_b) + t; }
  // The rotation and translation as an SE3 (ignores the scale).
  SE3 rigidPart() const { return SE3(R, t); }
};

// Returns S_target_source minimising sum_i |target_i - S * source_i|^2.
// Errors: the sets differ in size, fewer than 3 points, or degenerate (all source points or
// all target points coincide, so no rotation is defined). Collinear or coplanar sets are
// accepted: the result is then a minimiser, though the rotation about the line of a collinear
// set is arbitrary.
Expected<Sim3> alignPoints(const std::vector<Vec3>& source, const std::vector<Vec3>& target,
                           AlignmentKind kind);

}  // namespace rgbdslam
