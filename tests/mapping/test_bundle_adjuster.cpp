// BundleAdjuster: the Ceres adapters (manifold, cost functions through the manifold), and
// synthetic bundle adjustment with known ground truth: accuracy with and without depth, scale,
// low parallax, outliers judged per residual, interruption, and degenerate problems.
#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <random>
#include <thread>
#include <vector>

#include "rgbdslam/mapping/bundle_adjuster.h"
#include "rgbdslam/model/residuals.h"

namespace rgbdslam {
namespace {

constexpr double kDegree = M_PI / 180.0;

PinholeCamera freiburg1Camera() {
  PinholeCamera c;
  c.fx = 517.306, c.fy = 516.469, c.cx = 318.643, c.cy = 255.314;
  c.k1 = 0.2624, c.k2 = -0.9531, c.p1 = -0.0054, c.p2 = 0.0026, c.k3 = 1.1633;
  return c;
}

Vec3 randomDirection(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vec3(n(rng), n(rng), n(rng)).normalized();
}

// ---------------------------------------------------------------------------------------
// Synthetic scene: keyframes along the x axis looking roughly along +z at points 'min_depth'
// to 'max_depth' in front; measurements with pixel noise 0.5 px * 2^level (half the default
// k = 0.987, as a tracker with sub-pixel refinement gives) and Kinect depth noise a d^2.
struct SceneSpec {
  int num_keyframes = 8;
  int num_points = 300;
  double baseline = 0.25;       // distance between consecutive keyframes [m]
  double first_baseline = -1;   // distance between the first two keyframes [m]; < 0: baseline
  double min_depth = 1.5;       // [m]
  double max_depth = 4.5;       // [m]
  double pixel_noise = 0.5;     // at level 0 [px]
  double depth_fraction = 0.9;  // share of observations with a depth reading
  double depth_noise = 1.0;     // depth noise in units of the model a d^2
  uint32_t seed = 1;
};

// One camera for all scenes, so a Scene can be copied without its problem pointing into it.
const PinholeCamera& sceneCamera() {
  static const PinholeCamera camera = freiburg1Camera();
  return camera;
}

struct Scene {
  const PinholeCamera& camera = sceneCamera();
  std::vector<SE3> T_w_c_true;
  std::vector<Vec3> p_w_true;
  BaProblem problem;  // measurements; keyframes and points at the ground truth
};

std::vector<SE3> makeTrajectory(const SceneSpec& spec, std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<SE3> poses;
  for (int i = 0; i < spec.num_keyframes; ++i) {
    const double first = spec.first_baseline < 0 ? spec.baseline : spec.first_baseline;
    const double x = i == 0 ? 0.0 : first + (i - 1) * spec.baseline;
    const Vec3 centre(x, 0.05 * unit(rng), 0.05 * unit(rng));
    const Vec3 w(2 * kDegree * unit(rng), 3 * kDegree * unit(rng), 2 * kDegree * unit(rng));
    poses.emplace_back(expSO3(w), centre);
  }
  return poses;
}

void addObservations(const SceneSpec& spec, std::mt19937& rng, Scene* scene) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const double a = 3.331e-3;
  for (int k = 0; k < spec.num_keyframes; ++k) {
    const SE3 T_c_w = scene->T_w_c_true[k].inverse();
    for (int j = 0; j < spec.num_points; ++j) {
      const Vec3 p_c = T_c_w * scene->p_w_true[j];
      const auto uv = scene->camera.project(p_c);
      if (!uv || !scene->camera.inImage(*uv, 8.0)) continue;
      BaObservation obs;
      obs.keyframe_index = k;
      obs.point_index = j;
      const double r = uniform(rng);
      obs.level = r < 0.6 ? 0 : (r < 0.85 ? 1 : 2);
      const double sigma = spec.pixel_noise * std::ldexp(1.0, obs.level);
      obs.uv = *uv + sigma * Eigen::Vector2d(gauss(rng), gauss(rng));
      if (uniform(rng) < spec.depth_fraction)
        obs.depth = p_c.z() + spec.depth_noise * a * p_c.z() * p_c.z() * gauss(rng);
      scene->problem.observations.push_back(obs);
    }
  }
}

Scene makeScene(const SceneSpec& spec) {
  std::mt19937 rng(spec.seed);
  Scene scene;
  scene.T_w_c_true = makeTrajectory(spec, rng);
  // Points inside the view of a random keyframe, so every point is seen by several.
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> depth(spec.min_depth, spec.max_depth);
  std::uniform_int_distribution<int> which(0, spec.num_keyframes - 1);
  for (int j = 0; j < spec.num_points; ++j) {
    const double z = depth(rng);
    const Vec3 p_c(0.55 * z * unit(rng), 0.42 * z * unit(rng), z);
    scene.p_w_true.push_back(scene.T_w_c_true[which(rng)] * p_c);
  }
  scene.problem.camera = &scene.camera;
  for (int k = 0; k < spec.num_keyframes; ++k)
    scene.problem.keyframes.push_back({k, scene.T_w_c_true[k], false});
  for (int j = 0; j < spec.num_points; ++j)
    scene.problem.points.push_back({j, scene.p_w_true[j], false});
  addObservations(spec, rng, &scene);
  return scene;
}

// Perturbs every free pose (1-5 cm, 1-2 degrees) and free point (2-5 cm).
void perturb(BaProblem* problem, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (BaKeyframe& kf : problem->keyframes) {
    if (kf.fixed) continue;
    const Vec3 dt = (0.01 + 0.04 * uniform(rng)) * randomDirection(rng);
    const Vec3 dw = (1.0 + uniform(rng)) * kDegree * randomDirection(rng);
    kf.T_w_c = SE3(expSO3(dw) * kf.T_w_c.rotationMatrix(), kf.T_w_c.translation() + dt);
  }
  for (BaPoint& point : problem->points) {
    if (!point.fixed) point.p_w += (0.02 + 0.03 * uniform(rng)) * randomDirection(rng);
  }
}

struct PoseErrors {
  double max_translation = 0.0;   // [m]
  double mean_translation = 0.0;  // [m]
  double max_rotation = 0.0;      // [rad]
};

PoseErrors poseErrors(const Scene& scene) {
  PoseErrors errors;
  const auto& kfs = scene.problem.keyframes;
  for (size_t k = 0; k < kfs.size(); ++k) {
    const double dt = (kfs[k].T_w_c.translation() - scene.T_w_c_true[k].translation()).norm();
    const double dr =
        logSO3(kfs[k].T_w_c.rotationMatrix().transpose() * scene.T_w_c_true[k].rotationMatrix())
            .norm();
    errors.max_translation = std::max(errors.max_translation, dt);
    errors.max_rotation = std::max(errors.max_rotation, dr);
    errors.mean_translation += dt / kfs.size();
  }
  return errors;
}

// Estimated over true distance between the first and the last camera centre.
double scaleRatio(const Scene& scene) {
  const auto& kfs = scene.problem.keyframes;
  return (kfs.back().T_w_c.translation() - kfs.front().T_w_c.translation()).norm() /
         (scene.T_w_c_true.back().translation() - scene.T_w_c_true.front().translation()).norm();
}

// Over the points that have observations (the others are not touched by the adjuster).
double rmsPointError(const Scene& scene) {
  std::vector<bool> observed(scene.p_w_true.size(), false);
  for (const BaObservation& obs : scene.problem.observations) observed[obs.point_index] = true;
  double sum = 0.0;
  int n = 0;
  for (size_t j = 0; j < scene.p_w_true.size(); ++j) {
    if (!observed[j]) continue;
    sum += (scene.problem.points[j].p_w - scene.p_w_true[j]).squaredNorm();
    ++n;
  }
  return std::sqrt(sum / std::max(n, 1));
}

BaOptions twoDimensionalOnly() {
  BaOptions options;
  options.use_depth = false;
  return options;
}

// ---------------------------------------------------------------------------------------
// Ceres adapters

TEST(BaCeresAdapters, ManifoldPlusIsLeftPerturbationAndMinusInvertsIt) {
  const ba_ceres::PoseManifold manifold;
  Vec6 xi, delta;
  xi << 0.3, -0.2, 1.0, 0.4, -0.1, 0.7;
  delta << 0.01, 0.02, -0.03, 0.02, -0.01, 0.005;
  const SE3 T = SE3::exp(xi);
  double x[7], x_plus[7];
  ba_ceres::poseToBlock(T, x);
  ASSERT_TRUE(manifold.Plus(x, delta.data(), x_plus));
  const SE3 expected = SE3::exp(delta) * T;
  EXPECT_LT((ba_ceres::poseFromBlock(x_plus).matrix() - expected.matrix()).norm(), 1e-12);
  Vec6 recovered;
  ASSERT_TRUE(manifold.Minus(x_plus, x, recovered.data()));
  EXPECT_LT((recovered - delta).norm(), 1e-12);
}

// The 7-column ambient Jacobians of the cost functions, chained by Ceres through the
// manifold's PlusJacobian, must give exactly the analytic tangent Jacobians / sigma, and agree
// with central differences taken through Manifold::Plus.
TEST(BaCeresAdapters, CostJacobiansThroughManifoldMatchAnalyticAndNumeric) {
  const PinholeCamera camera = freiburg1Camera();
  Vec6 xi;
  xi << 0.2, -0.1, 0.3, 0.1, 0.25, -0.15;
  const SE3 T_c_w = SE3::exp(xi);
  const Vec3 p_w = T_c_w.inverse() * Vec3(0.4, -0.3, 2.2);
  const Eigen::Vector2d uv(350.0, 180.0);
  const double sigma_2d = 1.974, depth = 2.1, sigma_d = NoiseModel{}.sigmaDepth(depth);

  ba_ceres::PoseManifold manifold;
  double pose[7];
  ba_ceres::poseToBlock(T_c_w, pose);
  Vec3 point = p_w;
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  problem.AddParameterBlock(pose, 7, &manifold);
  problem.AddResidualBlock(new ba_ceres::ReprojectionCost(&camera, uv, sigma_2d), nullptr, pose,
                           point.data());
  problem.AddResidualBlock(new ba_ceres::DepthCost(depth, sigma_d), nullptr, pose, point.data());

  std::vector<double> residuals;
  ceres::CRSMatrix crs;
  ASSERT_TRUE(
      problem.Evaluate(ceres::Problem::EvaluateOptions(), nullptr, &residuals, nullptr, &crs));
  ASSERT_EQ(crs.num_rows, 3);
  ASSERT_EQ(crs.num_cols, 9);  // 6 tangent + 3 point columns
  Eigen::Matrix<double, 3, 9> J = Eigen::Matrix<double, 3, 9>::Zero();
  for (int r = 0; r < crs.num_rows; ++r) {
    for (int i = crs.rows[r]; i < crs.rows[r + 1]; ++i) J(r, crs.cols[i]) = crs.values[i];
  }

  Eigen::Vector2d e;
  Eigen::Matrix<double, 2, 6> d2_d_xi;
  Eigen::Matrix<double, 2, 3> d2_d_pw;
  ASSERT_TRUE(reprojectionResidual(camera, T_c_w, p_w, uv, &e, &d2_d_xi, &d2_d_pw));
  double e_d = 0.0;
  Eigen::Matrix<double, 1, 6> dd_d_xi;
  Eigen::Matrix<double, 1, 3> dd_d_pw;
  ASSERT_TRUE(depthResidual(T_c_w, p_w, depth, &e_d, &dd_d_xi, &dd_d_pw));
  Eigen::Matrix<double, 3, 9> expected;
  expected << d2_d_xi / sigma_2d, d2_d_pw / sigma_2d, dd_d_xi / sigma_d, dd_d_pw / sigma_d;
  EXPECT_LT((J - expected).norm(), 1e-9 * expected.norm()) << "ceres\n"
                                                           << J << "\nanalytic\n"
                                                           << expected;
  EXPECT_NEAR(residuals[0], e.x() / sigma_2d, 1e-12);
  EXPECT_NEAR(residuals[2], e_d / sigma_d, 1e-12);

  // Numeric, through the manifold: columns of d(residuals)/d(delta) via Plus(x, +-h e_k).
  const double h = 1e-6;
  for (int k = 0; k < 6; ++k) {
    Vec6 delta = Vec6::Zero();
    delta[k] = h;
    double plus[7], minus[7];
    manifold.Plus(pose, delta.data(), plus);
    const Vec6 neg = -delta;
    manifold.Plus(pose, neg.data(), minus);
    Eigen::Vector3d r_plus, r_minus;
    for (auto [block, out] : {std::pair{plus, &r_plus}, std::pair{minus, &r_minus}}) {
      const SE3 T = ba_ceres::poseFromBlock(block);
      Eigen::Vector2d e2;
      double ed = 0.0;
      ASSERT_TRUE(reprojectionResidual(camera, T, p_w, uv, &e2));
      ASSERT_TRUE(depthResidual(T, p_w, depth, &ed));
      *out << e2 / sigma_2d, ed / sigma_d;
    }
    const Eigen::Vector3d numeric = (r_plus - r_minus) / (2 * h);
    EXPECT_LT((J.col(k) - numeric).norm(), 1e-5 * std::max(1.0, numeric.norm())) << "column " << k;
  }
}

// What InterruptCallback relies on (Ceres 2.1): a callback that returns
// SOLVER_TERMINATE_SUCCESSFULLY leaves the last accepted iterate in the user's blocks (the same
// as stopping by max_num_iterations there), whereas SOLVER_ABORT restores the initial values.
class StopAtIteration final : public ceres::IterationCallback {
 public:
  StopAtIteration(int iteration, ceres::CallbackReturnType how)
      : iteration_(iteration), how_(how) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    return s.iteration >= iteration_ ? how_ : ceres::SOLVER_CONTINUE;
  }

 private:
  int iteration_;
  ceres::CallbackReturnType how_;
};

std::vector<double> solveToyBa(int max_iterations, ceres::IterationCallback* callback) {
  SceneSpec spec;
  spec.num_keyframes = 4;
  spec.num_points = 60;
  Scene scene = makeScene(spec);
  perturb(&scene.problem, 7);
  ba_ceres::PoseManifold manifold;
  std::vector<std::array<double, 7>> poses(spec.num_keyframes);
  for (int k = 0; k < spec.num_keyframes; ++k) {
    ba_ceres::poseToBlock(scene.problem.keyframes[k].T_w_c.inverse(), poses[k].data());
  }
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  for (auto& pose : poses) problem.AddParameterBlock(pose.data(), 7, &manifold);
  problem.SetParameterBlockConstant(poses[0].data());
  for (const BaObservation& obs : scene.problem.observations) {
    problem.AddResidualBlock(new ba_ceres::ReprojectionCost(&scene.camera, obs.uv, 1.0), nullptr,
                             poses[obs.keyframe_index].data(),
                             scene.problem.points[obs.point_index].p_w.data());
  }
  ceres::Solver::Options options;
  options.max_num_iterations = max_iterations;
  options.function_tolerance = options.gradient_tolerance = options.parameter_tolerance = 0.0;
  options.linear_solver_type = ceres::DENSE_SCHUR;
  if (callback != nullptr) options.callbacks.push_back(callback);
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  std::vector<double> state;
  for (const auto& pose : poses) state.insert(state.end(), pose.begin(), pose.end());
  return state;
}

TEST(BaCeresAdapters, TerminatingCallbackKeepsLastAcceptedIterateButAbortRestoresStart) {
  const std::vector<double> start = solveToyBa(0, nullptr);
  const std::vector<double> after3 = solveToyBa(3, nullptr);
  StopAtIteration terminate(3, ceres::SOLVER_TERMINATE_SUCCESSFULLY);
  StopAtIteration abort(3, ceres::SOLVER_ABORT);
  const std::vector<double> terminated = solveToyBa(100, &terminate);
  const std::vector<double> aborted = solveToyBa(100, &abort);
  ASSERT_NE(start, after3);  // three iterations did move the poses
  EXPECT_EQ(terminated, after3);
  EXPECT_EQ(aborted, start);
}

// ---------------------------------------------------------------------------------------
// Synthetic bundle adjustment

TEST(BundleAdjuster, DepthBaRecoversPosesPointsAndScale) {
  Scene scene = makeScene(SceneSpec{});
  scene.problem.keyframes[0].fixed = true;  // the gauge
  perturb(&scene.problem, 11);
  const PoseErrors before = poseErrors(scene);
  const double points_before = rmsPointError(scene);
  const BaResult result = BundleAdjuster(BaOptions{}).solve(&scene.problem);
  const PoseErrors after = poseErrors(scene);
  std::printf(
      "[ depth BA ] %zu obs, pose error max %.2f mm / %.3f deg (before %.1f mm / %.2f deg), "
      "points rms %.1f mm (before %.1f), scale %.5f, sigma_T 2d %.2f depth %.2f, %d it, "
      "%.1f ms\n",
      scene.problem.observations.size(), 1e3 * after.max_translation, after.max_rotation / kDegree,
      1e3 * before.max_translation, before.max_rotation / kDegree, 1e3 * rmsPointError(scene),
      1e3 * points_before, scaleRatio(scene), result.sigma_t_2d, result.sigma_t_depth,
      result.iterations, result.solve_ms);
  EXPECT_EQ(result.status, BaResult::Status::kConverged) << toString(result.status);
  EXPECT_LT(after.max_translation, 0.004);
  EXPECT_LT(after.max_rotation, 0.1 * kDegree);
  // Points: limited by the depth noise (3-7 cm per reading at 3-4.5 m) and the short baseline.
  EXPECT_LT(rmsPointError(scene), 0.5 * points_before);
  EXPECT_NEAR(scaleRatio(scene), 1.0, 0.002);
  EXPECT_LT(result.final_cost, result.initial_cost);
  // Noise 0.5 px per axis against k = 0.987: 1.4826 * median(|r|) = 1.7456 * 0.507 = 0.885
  // before fitting; depth noise exactly a d^2: 1.
  EXPECT_GT(result.sigma_t_2d, 0.6);
  EXPECT_LT(result.sigma_t_2d, 1.0);
  EXPECT_NEAR(result.sigma_t_depth, 1.0, 0.2);
  for (size_t i = 0; i < scene.problem.observations.size(); ++i) {
    EXPECT_FALSE(result.outlier_2d[i]) << i;
    EXPECT_FALSE(result.outlier_depth[i]) << i;
  }
  // The gauge keyframe did not move.
  EXPECT_EQ(scene.problem.keyframes[0].T_w_c.matrix(), scene.T_w_c_true[0].matrix());
}

TEST(BundleAdjuster, TwoDimensionalBaWithTwoFixedKeyframesRecoversPoses) {
  Scene scene = makeScene(SceneSpec{});
  scene.problem.keyframes[0].fixed = true;  // two fixed keyframes fix the scale of 2-D BA
  scene.problem.keyframes[1].fixed = true;
  perturb(&scene.problem, 12);
  const BaResult result = BundleAdjuster(twoDimensionalOnly()).solve(&scene.problem);
  const PoseErrors after = poseErrors(scene);
  std::printf("[ 2-D BA   ] pose error max %.2f mm / %.3f deg, points rms %.2f mm, scale %.5f\n",
              1e3 * after.max_translation, after.max_rotation / kDegree, 1e3 * rmsPointError(scene),
              scaleRatio(scene));
  EXPECT_EQ(result.status, BaResult::Status::kConverged) << toString(result.status);
  EXPECT_LT(after.max_translation, 0.004);
  EXPECT_LT(after.max_rotation, 0.1 * kDegree);
  EXPECT_NEAR(scaleRatio(scene), 1.0, 0.002);
  EXPECT_EQ(result.sigma_t_depth, 0.0);  // no depth residuals
  for (size_t i = 0; i < result.outlier_depth.size(); ++i) ASSERT_FALSE(result.outlier_depth[i]);
}

// A map 10 % too large (monocular scale drift) with only the first keyframe fixed: the 2-D
// residuals cannot see the scale and 2-D BA leaves it; the depth residuals restore it.
TEST(BundleAdjuster, DepthResidualsFixTheScaleThat2dBaCannotSee) {
  for (const bool use_depth : {true, false}) {
    Scene scene = makeScene(SceneSpec{});
    scene.problem.keyframes[0].fixed = true;
    const Vec3 origin = scene.T_w_c_true[0].translation();
    for (auto& kf : scene.problem.keyframes) {
      kf.T_w_c = SE3(kf.T_w_c.rotation(), origin + 1.1 * (kf.T_w_c.translation() - origin));
    }
    for (auto& point : scene.problem.points) point.p_w = origin + 1.1 * (point.p_w - origin);
    BaOptions options;
    options.use_depth = use_depth;
    const BaResult result = BundleAdjuster(options).solve(&scene.problem);
    std::printf("[ scale    ] use_depth=%d: scale %.4f (start 1.1), sigma_T 2d %.2f\n", use_depth,
                scaleRatio(scene), result.sigma_t_2d);
    EXPECT_NE(result.status, BaResult::Status::kFailed);
    EXPECT_LT(result.sigma_t_2d, 1.0);  // both explain the images
    if (use_depth) {
      EXPECT_NEAR(scaleRatio(scene), 1.0, 0.005);
    } else {
      EXPECT_GT(scaleRatio(scene), 1.05);
    }
  }
}

// Little parallax where 2-D BA takes its scale: the two fixed keyframes are only 1 cm apart
// (points 2-5 m away, so 1-2 px of disparity), the others follow 10 cm apart. 2-D BA's scale
// then rests on that pair, and its error grows along the trajectory; the depth residuals
// give every keyframe its scale directly. Both fix the same two keyframes; mean over seeds.
TEST(BundleAdjuster, DepthBaBeats2dBaOnPosesWithLittleParallax) {
  constexpr int kSeeds = 3;
  double mean_error[2] = {0.0, 0.0};  // [depth BA, 2-D BA] mean translation error [m]
  for (uint32_t seed = 1; seed <= kSeeds; ++seed) {
    SceneSpec spec;
    spec.first_baseline = 0.01;
    spec.baseline = 0.1;
    spec.min_depth = 2.0;
    spec.max_depth = 5.0;
    spec.seed = seed;
    for (const bool use_depth : {true, false}) {
      Scene scene = makeScene(spec);
      scene.problem.keyframes[0].fixed = true;
      scene.problem.keyframes[1].fixed = true;
      perturb(&scene.problem, 30 + seed);
      BaOptions options;
      options.use_depth = use_depth;
      const BaResult result = BundleAdjuster(options).solve(&scene.problem);
      EXPECT_NE(result.status, BaResult::Status::kFailed);
      mean_error[use_depth ? 0 : 1] += poseErrors(scene).mean_translation / kSeeds;
    }
  }
  std::printf("[ parallax ] mean pose error: depth BA %.2f mm, 2-D BA %.2f mm\n",
              1e3 * mean_error[0], 1e3 * mean_error[1]);
  EXPECT_LT(mean_error[0], 0.5 * mean_error[1]);
  EXPECT_LT(mean_error[0], 0.002);
}

// Depth readings 4 times noisier than the model a d^2 (cluttered scenes, paper sec. V-B):
// weighting each kind by its estimated noise keeps the depth from outweighing the images.
TEST(BundleAdjuster, WeightingBySigmaTCopesWithNoisierDepthThanModelled) {
  constexpr int kSeeds = 3;
  double mean_error[2] = {0.0, 0.0};  // [weighted, fixed weights] mean translation error [m]
  double sigma_t_depth = 0.0;
  for (uint32_t seed = 1; seed <= kSeeds; ++seed) {
    SceneSpec spec;
    spec.depth_noise = 4.0;
    spec.seed = seed;
    for (const bool weighted : {true, false}) {
      Scene scene = makeScene(spec);
      scene.problem.keyframes[0].fixed = true;
      perturb(&scene.problem, 40 + seed);
      BaOptions options;
      options.weight_by_sigma_t = weighted;
      const BaResult result = BundleAdjuster(options).solve(&scene.problem);
      EXPECT_NE(result.status, BaResult::Status::kFailed);
      mean_error[weighted ? 0 : 1] += poseErrors(scene).mean_translation / kSeeds;
      if (weighted) sigma_t_depth += result.sigma_t_depth / kSeeds;
    }
  }
  std::printf(
      "[ weights  ] depth noise 4x model: mean pose error weighted %.2f mm, fixed %.2f mm, "
      "sigma_T depth %.2f\n",
      1e3 * mean_error[0], 1e3 * mean_error[1], sigma_t_depth);
  EXPECT_NEAR(sigma_t_depth, 4.0, 0.8);
  EXPECT_LT(mean_error[0], 0.8 * mean_error[1]);
}

TEST(BundleAdjuster, OutliersAreJudgedPerResidual) {
  Scene scene = makeScene(SceneSpec{});
  scene.problem.keyframes[0].fixed = true;
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  auto& observations = scene.problem.observations;
  std::vector<bool> bad_2d(observations.size(), false), bad_depth(observations.size(), false);
  for (size_t i = 0; i < observations.size(); ++i) {
    if (uniform(rng) < 0.05) {
      const double angle = 2 * M_PI * uniform(rng);
      observations[i].uv += 20.0 * Eigen::Vector2d(std::cos(angle), std::sin(angle));
      bad_2d[i] = true;
    }
    if (observations[i].depth > 0 && uniform(rng) < 0.05) {
      observations[i].depth += uniform(rng) < 0.5 ? 0.5 : -0.5;
      bad_depth[i] = true;
    }
  }
  perturb(&scene.problem, 14);
  const BaResult result = BundleAdjuster(BaOptions{}).solve(&scene.problem);
  ASSERT_EQ(result.outlier_2d.size(), observations.size());
  int n_bad_2d = 0, caught_2d = 0, false_2d = 0, n_bad_d = 0, caught_d = 0, false_d = 0;
  int n_depth_only = 0, depth_only_flagged_2d = 0;
  for (size_t i = 0; i < observations.size(); ++i) {
    n_bad_2d += bad_2d[i];
    caught_2d += bad_2d[i] && result.outlier_2d[i];
    false_2d += !bad_2d[i] && result.outlier_2d[i];
    n_bad_d += bad_depth[i];
    caught_d += bad_depth[i] && result.outlier_depth[i];
    false_d += !bad_depth[i] && result.outlier_depth[i];
    if (bad_depth[i] && !bad_2d[i]) {
      ++n_depth_only;
      depth_only_flagged_2d += result.outlier_2d[i];
    }
  }
  const PoseErrors after = poseErrors(scene);
  std::printf(
      "[ outliers ] 2-D: %d/%d caught, %d false; depth: %d/%d caught, %d false; "
      "bad depth only -> 2-D flagged %d/%d; pose error max %.2f mm / %.3f deg\n",
      caught_2d, n_bad_2d, false_2d, caught_d, n_bad_d, false_d, depth_only_flagged_2d,
      n_depth_only, 1e3 * after.max_translation, after.max_rotation / kDegree);
  ASSERT_GT(n_bad_2d, 50);
  ASSERT_GT(n_bad_d, 50);
  // Nearly all: a point seen twice with one corrupted observation is ambiguous (either can be
  // the outlier), and a level-0 outlier can outweigh two good level-2 observations.
  EXPECT_GE(caught_2d, 0.95 * n_bad_2d);
  EXPECT_GE(caught_d, 0.95 * n_bad_d);
  EXPECT_LE(false_2d, 0.005 * observations.size());
  EXPECT_LE(false_d, 0.005 * observations.size());
  EXPECT_LE(depth_only_flagged_2d, 1);  // a bad depth reading does not reject the 2-D part
  EXPECT_LT(after.max_translation, 0.004);
  EXPECT_LT(after.max_rotation, 0.1 * kDegree);
}

TEST(BundleAdjuster, FixedKeyframesAndPointsDoNotMove) {
  Scene scene = makeScene(SceneSpec{});
  perturb(&scene.problem, 15);
  scene.problem.keyframes[0].fixed = true;
  scene.problem.keyframes[3].fixed = true;
  for (size_t j = 0; j < scene.problem.points.size(); j += 10) scene.problem.points[j].fixed = true;
  const BaProblem before = scene.problem;
  const BaResult result = BundleAdjuster(BaOptions{}).solve(&scene.problem);
  EXPECT_NE(result.status, BaResult::Status::kFailed);
  for (int k : {0, 3}) {
    EXPECT_EQ(scene.problem.keyframes[k].T_w_c.matrix(), before.keyframes[k].T_w_c.matrix());
  }
  EXPECT_NE(scene.problem.keyframes[2].T_w_c.matrix(), before.keyframes[2].T_w_c.matrix());
  for (size_t j = 0; j < scene.problem.points.size(); j += 10) {
    EXPECT_EQ(scene.problem.points[j].p_w, before.points[j].p_w);
  }
}

TEST(BundleAdjuster, InterruptFlagSetBeforeSolveReturnsAtOnceWithProblemUnchanged) {
  Scene scene = makeScene(SceneSpec{});
  scene.problem.keyframes[0].fixed = true;
  perturb(&scene.problem, 16);
  const BaProblem before = scene.problem;
  const std::atomic<bool> interrupt{true};
  const BaResult result = BundleAdjuster(BaOptions{}).solve(&scene.problem, &interrupt);
  EXPECT_EQ(result.status, BaResult::Status::kInterrupted) << toString(result.status);
  EXPECT_EQ(result.iterations, 0);
  for (size_t k = 0; k < before.keyframes.size(); ++k) {
    EXPECT_LT(
        (scene.problem.keyframes[k].T_w_c.matrix() - before.keyframes[k].T_w_c.matrix()).norm(),
        1e-12);
  }
  EXPECT_EQ(result.outlier_2d.size(), before.observations.size());
}

// The flag set from another thread while the solver runs: it stops early and the problem
// holds an accepted iterate (better than the start, not reverted to it). The flag is set
// halfway through the time an uninterrupted solve of the same problem takes.
TEST(BundleAdjuster, InterruptDuringSolveKeepsProgress) {
  SceneSpec spec;
  spec.num_keyframes = 12;
  spec.num_points = 800;
  Scene scene = makeScene(spec);
  scene.problem.keyframes[0].fixed = true;
  perturb(&scene.problem, 17);
  const PoseErrors before = poseErrors(scene);
  BaProblem uninterrupted = scene.problem;
  const BaResult full = BundleAdjuster(BaOptions{}).solve(&uninterrupted);
  ASSERT_GT(full.iterations, 4);

  std::atomic<bool> interrupt{false};
  std::thread setter([&] {
    std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(0.5 * full.solve_ms));
    interrupt = true;
  });
  const BaResult result = BundleAdjuster(BaOptions{}).solve(&scene.problem, &interrupt);
  setter.join();
  const PoseErrors after = poseErrors(scene);
  std::printf(
      "[ interrupt] after %d of %d iterations, %.1f of %.1f ms: pose error %.1f -> %.2f mm\n",
      result.iterations, full.iterations, result.solve_ms, full.solve_ms,
      1e3 * before.max_translation, 1e3 * after.max_translation);
  ASSERT_EQ(result.status, BaResult::Status::kInterrupted) << toString(result.status);
  EXPECT_LT(result.iterations, full.iterations);
  EXPECT_LE(result.final_cost, result.initial_cost);
  if (result.iterations > 0) {
    EXPECT_LT(after.max_translation, 0.5 * before.max_translation);
  }
}

TEST(BundleAdjuster, TooFewObservations) {
  const PinholeCamera camera = freiburg1Camera();
  BaProblem empty;
  empty.camera = &camera;
  EXPECT_EQ(BundleAdjuster(BaOptions{}).solve(&empty).status,
            BaResult::Status::kTooFewObservations);

  // Two free keyframes and one free point (15 unknowns) seen three times (9 residuals).
  Scene scene = makeScene(SceneSpec{});
  BaProblem tiny;
  tiny.camera = &scene.camera;
  tiny.keyframes = {scene.problem.keyframes[0], scene.problem.keyframes[1],
                    scene.problem.keyframes[2]};
  tiny.keyframes[0].fixed = true;
  tiny.points = {scene.problem.points[0]};
  for (int k = 0; k < 3; ++k) {
    const auto uv = camera.project(scene.T_w_c_true[k].inverse() * tiny.points[0].p_w);
    tiny.observations.push_back({k, 0, uv.value_or(Eigen::Vector2d(320, 240)), 0, 2.0});
  }
  const BaProblem before = tiny;
  const BaResult result = BundleAdjuster(BaOptions{}).solve(&tiny);
  EXPECT_EQ(result.status, BaResult::Status::kTooFewObservations);
  EXPECT_EQ(tiny.keyframes[1].T_w_c.matrix(), before.keyframes[1].T_w_c.matrix());
  EXPECT_EQ(tiny.points[0].p_w, before.points[0].p_w);
}

}  // namespace
}  // namespace rgbdslam
