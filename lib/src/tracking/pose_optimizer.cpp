#include "rgbdslam/tracking/pose_optimizer.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "rgbdslam/model/residuals.h"

namespace rgbdslam {
namespace {

constexpr double kMadToSigma = 1.4826;  // sigma of a Gaussian per median absolute deviation
constexpr int kMinObservations = 3;     // 6 unknowns, 2 equations each
constexpr double kExtraDamping = 1e-9;  // relative to the mean diagonal of J^T W J

// Linearised residuals at the current pose, normalised by their sigmas.
struct Linearisation {
  std::vector<Eigen::Vector2d> r2;
  std::vector<Eigen::Matrix<double, 2, 6>> J2;
  std::vector<uint8_t> valid2;
  std::vector<double> rd;
  std::vector<Eigen::Matrix<double, 1, 6>> Jd;
  std::vector<uint8_t> validd;
  std::vector<double> e2_2d, e2_depth;  // squared normalised errors of the valid ones
  std::vector<double> r_extra;          // ScalarResiduals, normalised
  std::vector<Eigen::Matrix<double, 1, 6>> J_extra;
  std::vector<double> e2_extra;
};

void linearise(const PinholeCamera& camera, const SE3& T_c_w,
               const std::vector<PoseObservation>& observations,
               const PoseOptimizerOptions& options, Linearisation* lin) {
  const size_t n = observations.size();
  lin->r2.resize(n);
  lin->J2.resize(n);
  lin->valid2.assign(n, 0);
  lin->rd.resize(n);
  lin->Jd.resize(n);
  lin->validd.assign(n, 0);
  lin->e2_2d.clear();
  lin->e2_depth.clear();
  for (size_t i = 0; i < n; ++i) {
    const PoseObservation& obs = observations[i];
    if (reprojectionResidual(camera, T_c_w, obs.p_w, obs.uv, &lin->r2[i], &lin->J2[i])) {
      const double inv_sigma = 1.0 / options.noise.sigma2d(obs.level);
      lin->r2[i] *= inv_sigma;
      lin->J2[i] *= inv_sigma;
      lin->valid2[i] = 1;
      lin->e2_2d.push_back(lin->r2[i].squaredNorm());
    }
    if (options.use_depth && obs.depth > 0.0 &&
        depthResidual(T_c_w, obs.p_w, obs.depth, &lin->rd[i], &lin->Jd[i])) {
      const double inv_sigma = 1.0 / options.noise.sigmaDepth(obs.depth);
      lin->rd[i] *= inv_sigma;
      lin->Jd[i] *= inv_sigma;
      lin->validd[i] = 1;
      lin->e2_depth.push_back(lin->rd[i] * lin->rd[i]);
    }
  }
}

}  // namespace

void PoseOptimizerOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "gauss_newton_iterations", &iterations, 1, 100, "iterations",
          "pose Gauss-Newton iterations per stage");
  r->bind(s, "tukey_c", &tukey_c, 1.0, 20.0, "sigmas", "Tukey biweight cut-off");
  r->bind(s, "min_robust_sigma", &min_robust_sigma, 0.01, 10.0, "sigmas",
          "floor of the robust scale estimated from the median error");
  r->bind(s, "max_robust_sigma", &max_robust_sigma, 0.0, 10.0, "sigmas",
          "cap of the robust scale after the free iterations, so many wrong matches cannot "
          "widen the cut-off (0: no cap)");
  r->bind(s, "free_scale_iterations", &free_scale_iterations, 0, 100, "iterations",
          "pose iterations per stage with the median scale uncapped, before the cap applies");
  r->bind(s, "use_depth_in_pose", &use_depth,
          "add depth residuals of tracked corners with a depth reading to the pose (never in "
          "mono, where depth serves only the first frame)");
  noise.bind(r);
}

double robustSigmaSquared(std::vector<double>* e2, double floor_sigma, double cap_sigma) {
  const double floor2 = floor_sigma * floor_sigma;
  if (e2->empty()) return floor2;
  const auto middle = e2->begin() + static_cast<std::ptrdiff_t>(e2->size() / 2);
  std::nth_element(e2->begin(), middle, e2->end());
  double sigma2 = std::max(floor2, kMadToSigma * kMadToSigma * *middle);
  if (cap_sigma > 0.0) sigma2 = std::min(sigma2, std::max(floor2, cap_sigma * cap_sigma));
  return sigma2;
}

PoseUncertainty poseUncertainty(const Eigen::Matrix<double, 6, 6>& information) {
  PoseUncertainty u;
  u.translation_m = u.rotation_rad = INFINITY;
  const Eigen::FullPivLU<Eigen::Matrix<double, 6, 6>> lu(information);
  if (!lu.isInvertible()) return u;
  const Eigen::Matrix<double, 6, 6> covariance = lu.inverse();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> t(covariance.topLeftCorner<3, 3>());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> r(covariance.bottomRightCorner<3, 3>());
  if (t.info() != Eigen::Success || r.info() != Eigen::Success) return u;
  u.translation_m = std::sqrt(std::max(0.0, t.eigenvalues().maxCoeff()));
  u.rotation_rad = std::sqrt(std::max(0.0, r.eigenvalues().maxCoeff()));
  return u;
}

PoseOptimizerResult optimisePose(const PinholeCamera& camera, const SE3& T_c_w_start,
                                 const std::vector<PoseObservation>& observations,
                                 const PoseOptimizerOptions& options,
                                 std::vector<uint8_t>* inlier, const ScalarResiduals* extra,
                                 const PosePrior* prior) {
  PoseOptimizerResult result;
  result.T_c_w = T_c_w_start;
  if (inlier) inlier->assign(observations.size(), 0);
  if (!extra && static_cast<int>(observations.size()) < kMinObservations) return result;
  Linearisation lin;
  const double c2 = options.tukey_c * options.tukey_c;
  for (int iteration = 0; iteration < options.iterations; ++iteration) {
    linearise(camera, result.T_c_w, observations, options, &lin);
    if (extra) {
      extra->linearise(result.T_c_w, &lin.r_extra, &lin.J_extra);
      lin.e2_extra.clear();
      for (double r : lin.r_extra) lin.e2_extra.push_back(r * r);
    }
    const int usable = static_cast<int>(lin.e2_2d.size() + lin.e2_extra.size());
    if ((extra ? usable : static_cast<int>(lin.e2_2d.size())) < kMinObservations) return result;
    const bool capped = iteration >= options.free_scale_iterations;
    const double cap = capped ? options.max_robust_sigma : 0.0;
    const double cut2_2d = c2 * robustSigmaSquared(&lin.e2_2d, options.min_robust_sigma, cap);
    const double cut2_depth = c2 * robustSigmaSquared(&lin.e2_depth, options.min_robust_sigma, cap);
    const double cut2_extra = c2 * robustSigmaSquared(&lin.e2_extra, options.min_robust_sigma, cap);
    Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
    int inliers_2d = 0, inliers_depth = 0;
    for (size_t i = 0; i < observations.size(); ++i) {
      if (lin.valid2[i]) {
        const double w = tukeyWeight(lin.r2[i].squaredNorm(), cut2_2d);
        if (inlier) (*inlier)[i] = w > 0.0;
        if (w > 0.0) {
          ++inliers_2d;
          H.noalias() += w * lin.J2[i].transpose() * lin.J2[i];
          b.noalias() += w * lin.J2[i].transpose() * lin.r2[i];
        }
      }
      if (lin.validd[i]) {
        const double w = tukeyWeight(lin.rd[i] * lin.rd[i], cut2_depth);
        if (w > 0.0) {
          ++inliers_depth;
          H.noalias() += w * lin.Jd[i].transpose() * lin.Jd[i];
          b.noalias() += (w * lin.rd[i]) * lin.Jd[i].transpose();
        }
      }
    }
    int inliers_extra = 0;
    Eigen::Matrix<double, 6, 6> H_extra = Eigen::Matrix<double, 6, 6>::Zero();
    for (size_t i = 0; i < lin.r_extra.size(); ++i) {
      const double w = tukeyWeight(lin.r_extra[i] * lin.r_extra[i], cut2_extra);
      if (w <= 0.0) continue;
      ++inliers_extra;
      H_extra.noalias() += w * lin.J_extra[i].transpose() * lin.J_extra[i];
      b.noalias() += (w * lin.r_extra[i]) * lin.J_extra[i].transpose();
    }
    result.inliers_2d = inliers_2d;
    result.inliers_depth = inliers_depth;
    H += H_extra;
    result.extra_residuals = static_cast<int>(lin.r_extra.size());
    result.inliers_extra = inliers_extra;
    if ((extra ? inliers_2d + inliers_extra : inliers_2d) < kMinObservations) return result;
    // Extra residuals may leave directions unfixed (one plane fixes three of six): a tiny
    // damping keeps the step in them at zero instead of undefined. The information matrix
    // reported stays undamped, so the uncertainty says what is unfixed.
    Eigen::Matrix<double, 6, 6> H_solve = H;
    if (extra) H_solve.diagonal().array() += kExtraDamping * std::max(1.0, H.trace() / 6.0);
    Eigen::Matrix<double, 6, 1> b_solve = b;
    if (prior) {
      // (r0 + xi)^T L (r0 + xi), r0 = log(T T_prior^-1): to first order in xi.
      const Vec6 r0 = (result.T_c_w * prior->T_c_w.inverse()).log();
      H_solve += prior->information;
      b_solve.noalias() += prior->information * r0;
    }
    const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> solver(H_solve);
    if (solver.info() != Eigen::Success) return result;
    // Minimise sum w |r + J xi|^2: J^T W J xi = -J^T W r.
    const Vec6 xi = solver.solve(-b_solve);
    if (!xi.allFinite()) return result;
    result.T_c_w = SE3::exp(xi) * result.T_c_w;
    result.iterations = iteration + 1;
    result.ok = true;
    result.information = H;
    result.extra_information = H_extra;
    // Converged: stop, unless the capped scale has yet to be tried (jump to it).
    if (xi.norm() < options.converged_step) {
      if (capped || options.max_robust_sigma <= 0.0 || iteration + 1 >= options.iterations) break;
      iteration = std::max(iteration, options.free_scale_iterations - 1);
    }
  }
  return result;
}

}  // namespace rgbdslam
