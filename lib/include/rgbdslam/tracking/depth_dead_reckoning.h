#pragma once
// Dead reckoning by depth while lost (issues 10 and 11: where the map's parts start).
//
// Lost, the tracker guessed where the camera went from the velocity at the loss alone, for
// at most TrackerOptions::relocalise_coast_frames: relocalisation tried that guess as a
// start, and a new part of the map started there. On the 10-minute flight the guess was off
// by 2.66 m and 25.1 deg at the median (up to 13.7 m and 105 deg) at 23 part starts, after
// 2-10 s lost (docs/open_work.md, session 37): the camera had turned, sped up or stopped
// meanwhile. Where the tracker is lost the image has failed it (a plain wall, a dark or
// blurred stretch); the depth image mostly has not. This follows the camera through the
// lost frames by depth alone.
//
// Model: the tracker's motion prior as it was at the last pose (motion_prior.h: the pose,
// the velocity and their covariance) predicts each lost frame's pose. The frame's depth is
// aligned point-to-plane (depth_alignment.h) against the surfaces of a recent frame held (the
// reference, renewed every DepthAlignmentOptions::reference_step_*, as in depth-aided
// tracking) and of the map's keyframes near the prediction, with the prediction as the fit's
// prior, so
// what the surfaces do not fix (the slide along a corridor's walls) follows the velocity.
// The surfaces' honest information (PointToPlaneResiduals::honestInformation) weighs the
// fit's move against the prediction, and updates the filter; its velocity follows by
// conditioning, as while tracking. In the directions the surfaces do not fix, the
// prediction and the velocity stay (see step()). A frame that would raise the speed or the
// turn rate beyond the vehicle's (MotionPriorOptions::max_speed_m_s, max_rate_rad_s) is not
// held.
// A frame is held when enough samples agree (DepthAlignmentOptions::min_inliers,
// min_inlier_ratio), the surfaces fix at least one direction, the fit's move in the
// directions kept lies within the prediction's 99.9 % ellipsoid (chi-square, 6 degrees of
// freedom: a fit further off settled in another basin of the surfaces), and the velocity
// stays within the vehicle's reach (as above). A frame
// not held leaves the filter as it was; none held for MotionPriorOptions::max_gap_s, or time
// going back, ends the dead reckoning (the velocity is too old to follow by). The caller
// coasts the last pose held on by the velocity, as it coasts from the last pose tracked.
//
// What it is not: a published pose. The tracker stays lost (depth alone does not vouch for a
// pose a flight controller may follow: depth_alignment.h); the guess only seeds the
// relocalisation's start and a new part's pose (tracker.cpp, lostPoseGuess).
//
// Needs the motion prior (MotionPriorOptions::enabled): without it nothing starts.
//
// Cost per frame: a fit over the samples of at most DepthAlignmentOptions::keyframes
// keyframes and the reference, and sampleSurface of a frame that renews the reference.
#include <cstdint>
#include <optional>
#include <vector>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/geometry/se3.h"
#include "rgbdslam/image/rgbd_frame.h"
#include "rgbdslam/model/noise_model.h"
#include "rgbdslam/tracking/depth_alignment.h"
#include "rgbdslam/tracking/motion_prior.h"
#include "rgbdslam/tracking/pose_optimizer.h"

namespace rgbdslam {

class DepthDeadReckoning {
 public:
  // 'min_depth_m' / 'max_depth_m': readings outside count as none (KeyframeBuildOptions).
  // 'fixed_sigma_m' / 'fixed_sigma_rad': the surfaces fix a direction of the pose when
  // they hold it within these (TrackerOptions::relocalise_reckoning_sigma_*); elsewhere the
  // prediction stays.
  DepthDeadReckoning(const PinholeCamera& camera, const DepthAlignmentOptions& align, const PoseOptimizerOptions& pose,
                     double min_depth_m, double max_depth_m, double fixed_sigma_m, double fixed_sigma_rad);

  // From the last pose, as the tracker's motion prior holds it there. A prior without a pose
  // (disabled) starts nothing.
  void start(const MotionPrior& at_last_pose);
  void stop();
  bool running() const { return running_; }

  // The pose predicted for a frame at 'utime' (T_c_w), to choose the map's surfaces near it;
  // none when not running or 'utime' is out of the prior's range.
  std::optional<SE3> predict(int64_t utime) const;
  // One lost frame, aligned against 'map_anchors' (world frame) and the last frame held.
  // True when it held (the filter took its pose).
  bool step(const RgbdFrame& frame, const std::vector<SurfaceAnchor>& map_anchors);
  // Where the camera is taken to be at 'utime' (T_c_w): the last frame held, carried on by
  // the velocity for at most 'max_coast_s'. None when no frame was held since start().
  std::optional<SE3> poseAt(int64_t utime, double max_coast_s) const;
  // Whether a frame was held within MotionPriorOptions::max_gap_s before 'utime'.
  bool heldRecently(int64_t utime) const;
  // The world frame moved (a map correction while lost): new = T_new_old * old.
  void moveWorld(const SE3& T_new_old);
  int framesHeld() const { return held_; }  // since start()
  // The velocity the filter holds (twist on T_c_w, [m/s, rad/s]); meaningful while running.
  const Vec6& velocity() const { return prior_.velocity(); }

 private:
  PinholeCamera camera_;
  DepthAlignmentOptions align_;
  PoseOptimizerOptions pose_;
  double min_depth_m_, max_depth_m_;
  Mat6 bar_ = Mat6::Zero();  // the information of a pose held within fixed_sigma_*
  bool running_ = false;
  int held_ = 0;
  MotionPrior prior_;
  std::vector<SurfaceSample> reference_;  // a recent frame held: its surfaces, its pose
  SE3 T_w_reference_;
  std::vector<SurfaceAnchor> anchors_;  // scratch
};

}  // namespace rgbdslam
