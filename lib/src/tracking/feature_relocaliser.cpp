#include "rgbdslam/tracking/feature_relocaliser.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <opencv2/features2d.hpp>
#include <random>

#include "rgbdslam/util/hamming.h"

namespace rgbdslam {
namespace {

constexpr uint32_t kRelocRansacSeed = 20261124;  // fixed: the same frame gives the same pose

struct FeatureMatch {
  int frame = 0, keyframe = 0;
};

// Nearest neighbour of each frame descriptor among the keyframe's, kept when it beats the
// second nearest by Lowe's ratio.
std::vector<FeatureMatch> matchByRatio(const cv::Mat& frame, const cv::Mat& keyframe, double ratio) {
  std::vector<FeatureMatch> matches;
  for (const cv::Mat* d : {&frame, &keyframe}) {
    if (d->rows > 0 && (d->type() != CV_8UC1 || d->cols != kBinaryDescriptorBytes)) return matches;
  }
  for (int i = 0; i < frame.rows; ++i) {
    int best = INT32_MAX, second = INT32_MAX, best_j = -1;
    for (int j = 0; j < keyframe.rows; ++j) {
      const int d = hamming256(frame.ptr<uint8_t>(i), keyframe.ptr<uint8_t>(j));
      if (d < best) {
        second = best;
        best = d;
        best_j = j;
      } else if (d < second) {
        second = d;
      }
    }
    if (best_j >= 0 && best < ratio * second) matches.push_back({i, best_j});
  }
  return matches;
}

// Rigid transform (no scale) taking src to dst, least squares (Umeyama).
SE3 rigidFit(const Eigen::Matrix3Xd& src, const Eigen::Matrix3Xd& dst) {
  const Eigen::Matrix4d T = Eigen::umeyama(src, dst, false);
  return SE3(Mat3(T.topLeftCorner<3, 3>()), Vec3(T.topRightCorner<3, 1>()));
}

}  // namespace

void FeatureRelocaliserOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "reloc_features", &enabled,
          "when lost, match ORB features of the frame and of the best keyframes with depth and "
          "find the pose by 3-D RANSAC (depth modes), besides PTAM's keyframe views");
  r->bind(s, "reloc_features_per_image", &features, 50, 5000, "features", "ORB features per image at most");
  r->bind(s, "reloc_features_candidates", &candidates, 1, 100, "keyframes",
          "keyframes matched, in the small blurry images' order");
  r->bind(s, "reloc_features_ratio", &ratio, 0.1, 1.0, "", "Lowe's ratio test: nearest / second nearest distance");
  r->bind(s, "reloc_ransac_iterations", &ransac_iterations, 1, 100000, "samples", "3-point RANSAC samples");
  r->bind(s, "reloc_inlier_sigmas", &inlier_sigmas, 0.5, 100.0, "sigmas",
          "a match agrees within this many sigmas of both readings' depth noise");
  r->bind(s, "reloc_inlier_min_m", &inlier_min_m, 0.0, 1.0, "m", "...and at least within this");
  r->bind(s, "reloc_min_inliers", &min_inliers, 3, 100000, "matches",
          "fewer agreeing matches: no pose from this keyframe");
}

Features3d extractFeatures3d(const cv::Mat& grey, const cv::Mat& depth_m, const PinholeCamera& camera,
                             const FeatureRelocaliserOptions& options) {
  Features3d out;
  if (grey.empty() || depth_m.empty() || depth_m.type() != CV_32FC1 || depth_m.size() != grey.size()) return out;
  const cv::Ptr<cv::ORB> orb = cv::ORB::create(options.features);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  orb->detectAndCompute(grey, cv::noArray(), keypoints, descriptors);
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const cv::Point2f& pt = keypoints[i].pt;
    const int u = static_cast<int>(std::lround(pt.x)), v = static_cast<int>(std::lround(pt.y));
    if (u < 0 || v < 0 || u >= depth_m.cols || v >= depth_m.rows) continue;
    const float z = depth_m.at<float>(v, u);
    if (!(z > 0.f)) continue;
    out.p.push_back(camera.unproject(Eigen::Vector2d(pt.x, pt.y), z).cast<float>());
    out.uv.emplace_back(pt.x, pt.y);
    out.descriptors.push_back(descriptors.row(static_cast<int>(i)));
  }
  return out;
}

std::optional<FeaturePose> poseFromFeatures(const Features3d& frame, const Features3d& keyframe,
                                            const SE3& T_w_k, const PinholeCamera& camera,
                                            const PoseOptimizerOptions& pose_options,
                                            const FeatureRelocaliserOptions& options) {
  const NoiseModel& noise = pose_options.noise;
  if (frame.size() < 3 || keyframe.size() < 3) return std::nullopt;
  const std::vector<FeatureMatch> matches = matchByRatio(frame.descriptors, keyframe.descriptors, options.ratio);
  const int n = static_cast<int>(matches.size());
  if (n < std::max(3, options.min_inliers)) return std::nullopt;
  // src: the frame's points (camera frame); dst: the keyframe's (its camera frame).
  Eigen::Matrix3Xd src(3, n), dst(3, n);
  std::vector<double> tolerance2(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    src.col(i) = frame.p[static_cast<size_t>(matches[i].frame)].cast<double>();
    dst.col(i) = keyframe.p[static_cast<size_t>(matches[i].keyframe)].cast<double>();
    const double sigma = std::hypot(noise.sigmaDepth(src(2, i)), noise.sigmaDepth(dst(2, i)));
    const double tolerance = std::max(options.inlier_min_m, options.inlier_sigmas * sigma);
    tolerance2[static_cast<size_t>(i)] = tolerance * tolerance;
  }
  auto inliersOf = [&](const SE3& T_k_c, std::vector<int>* ids) {
    ids->clear();
    for (int i = 0; i < n; ++i) {
      if ((T_k_c * Vec3(src.col(i)) - Vec3(dst.col(i))).squaredNorm() <= tolerance2[static_cast<size_t>(i)]) {
        ids->push_back(i);
      }
    }
  };
  std::mt19937 rng(kRelocRansacSeed);
  std::uniform_int_distribution<int> pick(0, n - 1);
  std::vector<int> best, ids;
  for (int iteration = 0; iteration < options.ransac_iterations; ++iteration) {
    const int a = pick(rng), b = pick(rng), c = pick(rng);
    if (a == b || b == c || a == c) continue;
    Eigen::Matrix3Xd s(3, 3), d(3, 3);
    s << src.col(a), src.col(b), src.col(c);
    d << dst.col(a), dst.col(b), dst.col(c);
    // Degenerate samples (nearly collinear) give an undefined rotation.
    if ((s.col(1) - s.col(0)).cross(s.col(2) - s.col(0)).norm() < 1e-4) continue;
    inliersOf(rigidFit(s, d), &ids);
    if (ids.size() > best.size()) best.swap(ids);
  }
  if (static_cast<int>(best.size()) < std::max(3, options.min_inliers)) return std::nullopt;
  // Refit on the inliers, then once more on the inliers of the refit.
  SE3 T_k_c;
  for (int round = 0; round < 2; ++round) {
    Eigen::Matrix3Xd s(3, static_cast<Eigen::Index>(best.size())), d(3, static_cast<Eigen::Index>(best.size()));
    for (size_t k = 0; k < best.size(); ++k) {
      s.col(static_cast<Eigen::Index>(k)) = src.col(best[k]);
      d.col(static_cast<Eigen::Index>(k)) = dst.col(best[k]);
    }
    T_k_c = rigidFit(s, d);
    inliersOf(T_k_c, &ids);
    if (static_cast<int>(ids.size()) < std::max(3, options.min_inliers)) return std::nullopt;
    best.swap(ids);
  }
  std::vector<PoseObservation> observations;
  for (int i : best) {
    const auto& m = matches[static_cast<size_t>(i)];
    const Eigen::Vector2f& uv = frame.uv[static_cast<size_t>(m.frame)];
    observations.push_back({T_w_k * Vec3(dst.col(i)), uv.cast<double>(), 0, src(2, i)});
  }
  const SE3 T_w_c = T_w_k * T_k_c;
  const PoseOptimizerResult refined = optimisePose(camera, T_w_c.inverse(), observations, pose_options);
  const SE3 pose = refined.ok ? refined.T_c_w.inverse() : T_w_c;
  FeaturePose result{pose, n, static_cast<int>(best.size()), {}};
  for (int i : best) result.inlier_matches.emplace_back(matches[static_cast<size_t>(i)].frame, matches[static_cast<size_t>(i)].keyframe);
  return result;
}

}  // namespace rgbdslam
