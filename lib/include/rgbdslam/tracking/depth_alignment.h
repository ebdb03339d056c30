#pragma once
// Depth-aided tracking (issue 12): where the image gives too few points to fix the pose (a
// plain wall, a dark or blurred stretch), the depth image constrains it by point-to-plane
// alignment against the depth of nearby keyframes.
//
// Model: each keyframe keeps surface samples on a grid (sampleSurface): a point and the
// normal of the plane fitted to the depth around it, in the keyframe's camera frame, only
// where the surface is locally flat (depth edges and clutter give no sample). For a pose
// T_c_w, a sample projects to the nearest pixel of the frame; the frame's reading there,
// back-projected to q_c, gives the point-to-plane residual r = n_c . (q_c - p_c), with p_c
// and n_c the sample in the camera frame (projective data association, as KinectFusion).
// Its sigma: the reading's axial noise and the sample's (the noise model's a z^2; the
// sample's divided by the square root of the readings its plane fit used). The residuals
// join the 2-D (and depth) residuals of the found points in one Gauss-Newton fit
// (pose_optimizer.h, ScalarResiduals) with their own robust scale, so the pose's
// information matrix, and hence its uncertainty, counts what depth fixes: a single plane
// fixes three degrees of freedom (distance, two tilts), two planes five, a corner all six.
// What depth does not fix must still come from the points, or the pose is lost.
//
// Why a fallback and not always: the samples of one surface share the sensor's systematic
// error (calibration, depth distortion); hundreds of them would outweigh a few hundred
// well-found corners with errors that are not independent. So depth joins the fit only when
// the points alone are weak (DepthAlignmentOptions::below_points, or a pose the points do
// not fix), and a frame held by depth is reported dodgy: the flight controller sees that
// vision alone did not hold the pose.
//
// Cost: sampleSurface once per keyframe (a 3x3 plane fit per sample); per iteration one
// projection and one depth lookup per sample of the aligned keyframes.
#include <string>
#include <vector>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/geometry/se3.h"
#include "rgbdslam/image/rgbd_frame.h"
#include "rgbdslam/model/noise_model.h"
#include "rgbdslam/tracking/pose_optimizer.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct DepthAlignmentOptions {
  bool enabled = true;            // in the modes that track with depth
  // Depth joins the fit when fewer points than this are found, or they do not fix the pose
  // [points]. Measured on the synthetic corridor (900 frames, weak texture; the points alone
  // fix every pose there): at 40, 114 frames with 20-40 points were depth-aided and the run
  // got worse (ATE 18.9 -> 22.9 mm, end 0.064 -> 0.22 %); at 20 none were, byte-identical.
  // Points that fix the pose are the better measurement; depth is the fallback.
  int below_points = 20;
  int keyframes = 2;              // nearest keyframes whose samples are aligned against
  int grid_px = 16;               // one surface sample per grid cell [px]
  double fit_radius_m = 0.1;      // plane fit over this radius around a sample [m]
  double max_plane_rms_sigmas = 2.0;  // flat: fit residual RMS within this many depth sigmas
  double max_incidence_deg = 75.0;    // samples seen more obliquely than this are skipped [deg]
  // The samples share the sensor's systematic errors (calibration, depth distortion, the
  // plane fits' bias at grazing angles), so in the pose's uncertainty they count as at most
  // this many independent measurements. Measured: in the room with the lights out, depth
  // alone held the pose within 1-3 cm for 50 frames, then slid 50 cm in 15 frames while
  // the fit's own uncertainty, from 1500 samples, said 1.5 cm.
  int effective_samples = 100;
  int min_inliers = 100;          // fewer samples agreeing with the pose: depth does not hold it
  // The aligned pose must lie within this of the motion model's prediction (constant
  // velocity): an alignment that moves the camera further settled in another basin of the
  // surfaces (measured on the office with every sensor effect: jumps of up to 28 cm in
  // depth-aided frames), and a vehicle's velocity does not change that much in one frame.
  double max_step_m = 0.05;       // [m]
  double max_step_deg = 5.0;      // [deg]
  double min_inlier_ratio = 0.5;  // ...nor when fewer than this fraction of those associated agree
  // The depth reference: a depth-aided frame's own surfaces join the next frames' alignment,
  // so that depth keeps holding the pose where the camera has moved past the keyframes' view
  // (a plain office: lost for good once the two nearest keyframes' surfaces left the image).
  // A new reference is taken from an accepted depth-aided frame once the camera is this far
  // from the last one's pose. Each new reference passes its alignment error on, as in frame-
  // to-keyframe depth odometry (DVO-SLAM, KinectFusion), so fewer references drift less;
  // the map's keyframes stay in the fit and hold the pose wherever they are in view.
  // 0 turns the reference off.
  double reference_step_m = 0.1;     // [m]
  double reference_step_deg = 10.0;  // [deg]

  void bind(OptionRegistry* registry, const std::string& section);  // as depth_align_*
};

// A surface sample in its keyframe's camera frame.
struct SurfaceSample {
  Eigen::Vector3f p = Eigen::Vector3f::Zero();  // point on the fitted plane [m]
  Eigen::Vector3f n = Eigen::Vector3f::Zero();  // unit normal, towards the camera
  float sigma = 0.f;                            // noise of p along n [m]
  float normal_var = 0.f;                       // variance of n's tilt [rad^2]
};

// Samples of a metric depth image (CV_32FC1, NaN where there is no reading; KeyframeDepth::metres()).
std::vector<SurfaceSample> sampleSurface(const cv::Mat& depth_m, const PinholeCamera& camera,
                                         const NoiseModel& noise, const DepthAlignmentOptions& options);

// A sample in the world frame, for one frame's alignment.
struct SurfaceAnchor {
  Vec3 p_w = Vec3::Zero();
  Vec3 n_w = Vec3::Zero();
  double sigma = 0.0;  // [m]
  double normal_var = 0.0;  // [rad^2]
};

// Appends 'samples' of a keyframe at T_w_k to 'anchors'.
void appendAnchors(const std::vector<SurfaceSample>& samples, const SE3& T_w_k,
                   std::vector<SurfaceAnchor>* anchors);

// The point-to-plane residuals of 'anchors' against one frame's depth (CV_16UC1 raw,
// readings outside [min_depth_m, max_depth_m] count as none), for optimisePose.
class PointToPlaneResiduals : public ScalarResiduals {
 public:
  PointToPlaneResiduals(const std::vector<SurfaceAnchor>& anchors, const RgbdFrame& frame,
                        const PinholeCamera& camera, const NoiseModel& noise, double min_depth_m,
                        double max_depth_m, double max_incidence_deg);
  void linearise(const SE3& T_c_w, std::vector<double>* r,
                 std::vector<Eigen::Matrix<double, 1, 6>>* J) const override;
  // What the samples' normal errors added to J^T J at the last linearise(), all residuals
  // counted at full weight: noisy normals of one plane point in every direction a little, so
  // their J^T J claims to fix the slide along the plane that nothing fixes. The fit's
  // information minus this is what the surfaces really fix (for the pose's uncertainty).
  const Eigen::Matrix<double, 6, 6>& normalNoiseInformation() const { return normal_noise_information_; }
  // J^T J of the last linearise() (all residuals at full weight).
  const Eigen::Matrix<double, 6, 6>& information() const { return information_; }
  // What the surfaces fix, for the uncertainty: their robustly weighted J^T W J from the fit
  // ('weighted', PoseOptimizerResult::extra_information) less the normals' share, scaled
  // down to 'effective_samples' independent ones when 'samples' agreed.
  Eigen::Matrix<double, 6, 6> honestInformation(const Eigen::Matrix<double, 6, 6>& weighted,
                                                int effective_samples, int samples) const;

 private:
  const std::vector<SurfaceAnchor>& anchors_;
  const RgbdFrame& frame_;
  const PinholeCamera& camera_;
  NoiseModel noise_;
  uint16_t raw_min_ = 1, raw_max_ = 65535;
  double min_cos_incidence_ = 0.0;
  mutable Eigen::Matrix<double, 6, 6> normal_noise_information_ = Eigen::Matrix<double, 6, 6>::Zero();
  mutable Eigen::Matrix<double, 6, 6> information_ = Eigen::Matrix<double, 6, 6>::Zero();
};

}  // namespace rgbdslam
