#pragma once
// Relocalisation from anywhere in the map's keyframes (issue 11, item 3). PTAM's relocaliser
// (relocaliser.h) tries a keyframe's own pose, turned by the small blurry images' rotation:
// the tracker converges from there only when the camera is within a few degrees and
// centimetres of that view. After a 2 s gap the camera is 30+ degrees and 0.3 m away.
//
// With depth both views are 3-D: each keyframe keeps ORB features (oriented FAST with rBRIEF
// descriptors, OpenCV) where its depth has a reading, as points in its camera frame. A lost
// frame extracts the same; descriptors are matched (nearest neighbour, Lowe's ratio test);
// RANSAC on 3-point samples (Umeyama's rigid fit) finds the pose that brings most matched
// points onto each other within the depth noise of both readings; the inliers' fit gives the
// pose, from which the tracker then tracks the map's points as usual (a wrong pose fails
// there and in the depth integrity check).
// Which keyframes: the small blurry images' ranking over all keyframes (relocaliser.h) picks
// the candidates; matching every keyframe would cost ~2 ms each.
// Cost: ORB on one 640x480 frame ~4-6 ms (once per lost frame); matching 500 x 500 descriptors
// ~1-2 ms per candidate; RANSAC ~0.1 ms. Memory: 52 bytes a feature, at most 26 kB per keyframe.
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/geometry/se3.h"
#include "rgbdslam/model/noise_model.h"
#include "rgbdslam/tracking/pose_optimizer.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct FeatureRelocaliserOptions {
  bool enabled = true;          // in the modes that track with depth
  int features = 500;           // ORB features per image at most
  int candidates = 4;           // keyframes matched, best small-blurry-image rank first
  double ratio = 0.8;           // Lowe's ratio: nearest / second-nearest Hamming distance
  int ransac_iterations = 200;  // 3-point samples
  double inlier_sigmas = 3.0;   // a match agrees within this many sigmas of both readings' noise
  double inlier_min_m = 0.01;   // ...and at least this [m]
  int min_inliers = 15;         // fewer agreeing matches: no pose from this keyframe

  void bind(OptionRegistry* registry, const std::string& section);  // as reloc_features_* ...
};

// ORB features with a depth reading, as 3-D points in their image's camera frame.
struct Features3d {
  std::vector<Eigen::Vector3f> p;  // [m]
  std::vector<Eigen::Vector2f> uv;  // where it was found, level 0 [px]
  cv::Mat descriptors;             // CV_8UC1, one 32-byte row per point
  size_t size() const { return p.size(); }
};

// 'grey' CV_8UC1; 'depth_m' CV_32FC1 in metres, NaN or 0 where there is no reading.
Features3d extractFeatures3d(const cv::Mat& grey, const cv::Mat& depth_m, const PinholeCamera& camera,
                             const FeatureRelocaliserOptions& options);

struct FeaturePose {
  SE3 T_w_c;
  int matches = 0;  // after the ratio test
  int inliers = 0;
  std::vector<std::pair<int, int>> inlier_matches;  // (frame feature, keyframe feature) of each inlier
};

// The pose of the frame whose features are 'frame' from the features of a keyframe at
// T_w_k; nullopt when fewer than min_inliers matches agree. The RANSAC inliers' rigid fit
// weighs every point alike, though depth noise grows with z^2 (measured: 6 cm off after
// the room's 2 s gap), so the pose is then refined by the tracker's own fit (2-D position
// and depth of each inlier, each with its noise; pose_optimizer.h). Deterministic.
std::optional<FeaturePose> poseFromFeatures(const Features3d& frame, const Features3d& keyframe,
                                            const SE3& T_w_k, const PinholeCamera& camera,
                                            const PoseOptimizerOptions& pose_options,
                                            const FeatureRelocaliserOptions& options);

}  // namespace rgbdslam
