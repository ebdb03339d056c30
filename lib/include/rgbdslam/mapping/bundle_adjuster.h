#pragma once
// Bundle adjustment with 2-D and depth residuals (paper sec. IV; ARCHITECTURE.md "Bundle
// adjustment with depth"). Minimises over the free keyframe poses and point positions
//   sum_ij rho(|e2_ij| / sigma2_ij) + sum_ij rho(|ed_ij| / sigmad_ij)
// with the residuals of model/residuals.h, sigma2 = k 2^level [px], sigmad = a d^2 [m] (the
// measured d; model/noise_model.h) and rho Tukey's biweight (ceres::TukeyLoss, a = tukey_c * sigma_T, on each
// residual block on its own), solved by Levenberg-Marquardt with Schur elimination of the
// points.
//
// Robust rounds: sigma_T is estimated from the median of the normalised errors, separately
// for the 2-D and the depth residuals (formulas and reasons in bundle_adjuster.cpp), then the
// problem is solved; this repeats while the estimate keeps falling (at most robust_rounds
// times), sigma_T stepping down by at most sigma_t_max_shrink per round. Each kind is also
// weighted by its estimated noise (weight_by_sigma_t). Observations are outliers when their
// normalised error exceeds tukey_c * sigma_T at the solution. sigma_T is estimated from the
// observations of points with redundancy (more residual rows than unknowns) only.
// Free points that cannot be located are left out or held: a point with a single
// observation and no depth is left out (not judged); a point whose inlier residuals no longer
// locate it (no 2-D inlier, or fewer than 3 inlier rows) is held constant for that round.
//
// Call order: fill a BaProblem (keyframes with T_w_c, points with p_w, observations naming
// them by index; mark the gauge keyframe(s) fixed), call BundleAdjuster::solve(), read the
// optimised T_w_c / p_w back from the problem and the per-observation outlier flags from the
// result. The caller fixes the gauge: at least the first keyframe with depth residuals, and
// in 2-D-only mode also the scale (a second keyframe, or points); nothing here fixes it.
//
// Threads: solve() is const and keeps no state between calls; it may run in the mapper's
// thread while another thread sets *interrupt (e.g. when a new keyframe arrives). It then
// returns kInterrupted promptly and the problem holds the last accepted iterate.
#include <ceres/manifold.h>
#include <ceres/sized_cost_function.h>

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/geometry/se3.h"
#include "rgbdslam/model/noise_model.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct BaOptions {
  enum class LinearSolver {
    kAuto,            // kDenseSchur up to dense_schur_max_poses free poses, else kSparseSchur
    kDenseSchur,      // Schur complement of the points, dense reduced camera system
    kSparseSchur,     // the same, sparse Cholesky (falls back to kIterativeSchur without a
                      // sparse library in this Ceres build)
    kIterativeSchur,  // conjugate gradients on the reduced camera system (Schur-Jacobi)
  };

  NoiseModel noise;                    // sigma2 and sigmad (bound as section "noise")
  bool use_depth = true;               // add the 1-D depth residuals (mode depth-ba); false: 2-D
                                       // only (modes mono and depth-init; the mapper turns it
                                       // off there)
  double tukey_c = 4.6851;             // Tukey biweight cut-off in units of sigma_T (95 %
                                       // efficiency under Gaussian noise); > 0
  double min_sigma_t = 0.5;            // floor of the robust scale sigma_T [units of sigma], so
                                       // that a perfect map (all errors ~0) does not make every
                                       // measurement an outlier; with the floor the cut-off is at
                                       // least tukey_c * 0.5 ~ 2.3 sigma; > 0
  bool weight_by_sigma_t = true;       // weight each residual kind by 1 / nu^2, nu = its noise
                                       // relative to the model, estimated with sigma_T (per-axis
                                       // for 2-D, floored at min_sigma_t). The paper fixes the
                                       // weights at 1 / sigma^2 (false), which is right only when
                                       // k and a fit the data; when one kind is noisier (e.g.
                                       // depth readings 4x worse than a d^2, or many of them
                                       // wrong), it then outweighs the other, whose residuals
                                       // the tight Tukey cut-off rejects instead, and the map
                                       // collapses. Cut-offs and outliers are the same either way.
  int max_iterations = 20;             // Levenberg-Marquardt iterations per solve; >= 1
  int robust_rounds = 6;               // IRLS outer loop: at most this many (estimate sigma_T,
                                       // solve) rounds; >= 1
  double sigma_t_max_shrink = 3.0;     // sigma_T may fall at most by this factor from one round
                                       // to the next (graduated). The first sigma_T comes from
                                       // the initial errors, inflated after a new keyframe; a
                                       // jump straight to the final, tight scale leaves a point
                                       // pulled off by an outlier with no inlier at all, and it
                                       // is lost. Stepping down lets it return first; > 1
  double sigma_t_settled_ratio = 0.8;  // stop the rounds once no sigma_T estimate is below
                                       // this fraction of the one last solved with; (0, 1]
  double function_tolerance = 1e-6;    // stop when |cost change| / cost < this [-]
  double gradient_tolerance = 1e-10;   // stop when max |gradient| < this (Ceres' scaling)
  double parameter_tolerance = 1e-8;   // stop when |step| / (|x| + tol) < this [-]
  int num_threads = 1;                 // Ceres threads (the mapper runs beside the tracker)
  LinearSolver linear_solver = LinearSolver::kAuto;
  int dense_schur_max_poses = 40;  // kAuto: dense Schur up to this many free poses [-]

  // Every field, as section.<field name> (noise as section "noise").
  void bind(OptionRegistry* registry, const std::string& section = "bundle_adjustment");
};

struct BaKeyframe {
  int64_t id = -1;     // the map's keyframe id (bookkeeping only)
  SE3 T_w_c;           // camera-to-world pose [m]; optimised in place unless fixed
  bool fixed = false;  // held constant (gauge keyframe, or outside the local window)
};

struct BaPoint {
  int64_t id = -1;          // the map's point id (bookkeeping only)
  Vec3 p_w = Vec3::Zero();  // position in the world [m]; optimised in place unless fixed
  bool fixed = false;       // held constant
};

struct BaObservation {
  int keyframe_index = -1;                       // index into BaProblem::keyframes
  int point_index = -1;                          // index into BaProblem::points
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  // measured pixel at level 0 [px]
  int level = 0;       // pyramid level the point was found at (sets sigma2d)
  double depth = 0.0;  // measured depth at the corner [m]; 0 = no reading
};

struct BaProblem {
  const PinholeCamera* camera = nullptr;  // level-0 calibration; must outlive solve()
  std::vector<BaKeyframe> keyframes;
  std::vector<BaPoint> points;
  std::vector<BaObservation> observations;
};

struct BaResult {
  enum class Status {
    kConverged,           // the last solve met a tolerance
    kMaxIterations,       // the last solve ran max_iterations without converging (the
                          // problem still holds its best iterate)
    kInterrupted,         // *interrupt became true; the problem holds the last accepted iterate
    kTooFewObservations,  // nothing usable, or fewer residuals than free parameters; the
                          // problem is unchanged
    kFailed,              // Ceres failed (e.g. a non-finite residual); the problem is unchanged
                          // since the last completed solve
  };
  Status status = Status::kFailed;
  int iterations = 0;          // Levenberg-Marquardt iterations over all rounds
  double initial_cost = 0.0;   // robust cost 1/2 sum rho(|e|^2 / sigma^2) before solving and
  double final_cost = 0.0;     // after, both with the first round's sigma_T (comparable) [-]
  double sigma_t_2d = 0.0;     // robust scale of the normalised 2-D error norms at the solution,
                               // 1.4826 median(|r|) [-]; = 1.75 s for Gaussian noise of s per
                               // axis, so ~1.75 when k matches the noise
  double sigma_t_depth = 0.0;  // the same for the depth errors, 1.4826 median(|r|) [-]; ~1 when
                               // a matches the noise (0 when there are no depth residuals)
  // Per observation, judged separately (a bad depth reading does not reject a good 2-D
  // observation): normalised error > tukey_c * sigma_T at the solution, or the point is
  // behind the camera. outlier_depth is false where no depth residual was used.
  std::vector<bool> outlier_2d;
  std::vector<bool> outlier_depth;
  double solve_ms = 0.0;  // wall time of solve() [ms]
};

const char* toString(BaResult::Status status);

class BundleAdjuster {
 public:
  explicit BundleAdjuster(BaOptions options);
  const BaOptions& options() const { return options_; }

  // Optimises the free poses and points of *problem in place (see the header comment).
  // 'interrupt' may be null; it is polled after every Levenberg-Marquardt iteration (and
  // before the first), so the call returns within one iteration of it becoming true.
  BaResult solve(BaProblem* problem, const std::atomic<bool>* interrupt = nullptr) const;

 private:
  BaOptions options_;
};

// ---------------------------------------------------------------------------------------
// Ceres adapters, used by BundleAdjuster and exposed for the tests.
//
// Pose parameter block: 7 doubles of T_c_w, the quaternion (x, y, z, w; Eigen's coeffs()
// order) then the translation [m]. Its tangent is the 6-D xi of the left perturbation
// T_c_w <- exp(xi) * T_c_w, the same as in model/residuals.h.
//
// Jacobian trick: a cost function must give Ceres the Jacobian with respect to the 7 ambient
// coordinates, and Ceres multiplies it by the manifold's PlusJacobian (7x6) to get the
// Jacobian in the tangent space. The cost functions write [d_res_d_xi | 0] (the analytic 6
// columns, then a zero column) and PoseManifold::PlusJacobian returns [I6; 0], so the product
// is exactly d_res_d_xi. The 7 columns are therefore NOT derivatives with respect to the
// quaternion and translation coordinates: the pair only works together, and Ceres' own
// gradient checker (Solver::Options::check_gradients) cannot be used on these costs; the
// tests compare the tangent Jacobians from ceres::Problem::Evaluate with numeric ones instead.
namespace ba_ceres {

constexpr int kPoseBlockSize = 7;
constexpr int kPoseTangentSize = 6;

void poseToBlock(const SE3& T_c_w, double* block);
SE3 poseFromBlock(const double* block);

class PoseManifold final : public ceres::Manifold {
 public:
  int AmbientSize() const override { return kPoseBlockSize; }
  int TangentSize() const override { return kPoseTangentSize; }
  // exp(delta) * T_c_w
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  // [I6; 0] (row-major 7x6): see the Jacobian trick above
  bool PlusJacobian(const double* x, double* jacobian) const override;
  // log(Y * X^-1), so that Plus(x, Minus(y, x)) = y
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  // [I6 | 0] (row-major 6x7)
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

// Normalised 2-D residual e / sigma; parameters: pose block, p_w. Returns false (Ceres
// rejects the step) when the point is behind the camera.
class ReprojectionCost final : public ceres::SizedCostFunction<2, kPoseBlockSize, 3> {
 public:
  ReprojectionCost(const PinholeCamera* camera, const Eigen::Vector2d& uv, double sigma)
      : camera_(camera), uv_(uv), inv_sigma_(1.0 / sigma) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  const PinholeCamera* camera_;
  Eigen::Vector2d uv_;  // [px]
  double inv_sigma_;    // [1/px]
};

// Normalised depth residual e_d / sigma; parameters: pose block, p_w.
class DepthCost final : public ceres::SizedCostFunction<1, kPoseBlockSize, 3> {
 public:
  DepthCost(double depth, double sigma) : depth_(depth), inv_sigma_(1.0 / sigma) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  double depth_;      // [m]
  double inv_sigma_;  // [1/m]
};

}  // namespace ba_ceres
}  // namespace rgbdslam
