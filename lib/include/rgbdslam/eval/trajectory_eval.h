#pragma once
// Trajectory evaluation against ground truth, as in the TUM RGB-D benchmark: absolute
// trajectory error (ATE) after aligning the estimate to the ground truth, and relative pose
// error (RPE) over a fixed time (1 s) and a fixed travelled distance (1 m). Also the
// frame-to-frame error, the figure a flight controller feels: between consecutive posed
// frames, |S(p_est,j) - S(p_est,i) - (p_gt,j - p_gt,i)| after the alignment S, its worst
// value and how many exceed jump_threshold_m (a jump).
//
// Call order: evaluateTrajectory(groundtruth, estimate, options) -> EvalResult, then any of
// toJson / toKeyValueText / writeTrajectoryPlot on the result.
//
// Frames and units: both trajectories hold T_w_c (camera to world), each in its own world
// frame; times in seconds, positions in metres (the estimate in its own units for a
// monocular run). The alignment S_gt_est maps the estimate's world into the ground truth's
// world (p_gt ~= S_gt_est * p_est); errors are reported in ground-truth metres and degrees.
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "rgbdslam/geometry/alignment.h"
#include "rgbdslam/io/trajectory_io.h"
#include "rgbdslam/util/expected.h"

namespace rgbdslam {

struct EvalOptions {
  double max_dt_s = 0.02;            // [s] largest |t_est - t_gt| for a pose pair to be associated
  bool similarity = false;           // align with a scale too (monocular); else rigid (scale 1)
  double rpe_delta_s = 1.0;          // [s] time step of the per-second RPE (ground-truth time)
  double rpe_delta_m = 1.0;          // [m] travelled ground-truth distance of the per-metre RPE
  std::optional<size_t> num_frames;  // frames given to the tracker, for coverage; unknown if empty
  double jump_threshold_m = 0.02;    // [m] frame-to-frame errors above this are counted as jumps
};

// Summary of a set of non-negative errors. All zero when count == 0.
struct ErrorStats {
  size_t count = 0;
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;  // mean of the two middle values for an even count
  double stddev = 0.0;  // population standard deviation (divides by count)
  double min = 0.0;
  double max = 0.0;
};
ErrorStats computeErrorStats(std::vector<double> values);

// One associated pose pair: indices into the ground-truth and the estimated trajectory.
struct PosePair {
  size_t gt_index = 0;
  size_t est_index = 0;
  double dt_s = 0.0;  // t_est - t_gt [s]
};

// Association by timestamp, one-to-one, as TUM's associate.py: among all (estimate,
// ground-truth) pairs with |dt| <= max_dt_s, take pairs greedily by increasing |dt| (ties by
// estimate index, then ground-truth index), skipping any whose estimate or ground-truth pose
// is already taken. So each estimate gets its nearest ground truth unless a closer estimate
// claimed that one first. The result is sorted by estimate time. Inputs need not be sorted.
std::vector<PosePair> associateByTime(const Trajectory& groundtruth, const Trajectory& estimate,
                                      double max_dt_s);

// Relative pose error over pose pairs (i, j) of the associated sequence where j is the first
// associated pose at least delta after i: E = (G_i^-1 G_j)^-1 (P_i^-1 P_j), with the
// estimate's translations multiplied by the ATE scale (similarity mode).
struct RpeResult {
  ErrorStats trans_m;  // |translation of E| [m]; count = number of (i, j) pairs
  ErrorStats rot_deg;  // rotation angle of E [deg]
};

struct EvalResult {
  AlignmentKind alignment = AlignmentKind::kRigid;
  EvalOptions options;             // the options used
  size_t num_estimate = 0;         // poses in the estimate
  size_t num_groundtruth = 0;      // poses in the ground truth
  size_t num_associated = 0;       // estimate poses paired with a ground-truth pose
  std::optional<double> coverage;  // min(1, num_associated / num_frames), if num_frames known
  Sim3 S_gt_est;                   // estimate world -> ground-truth world (scale 1 if rigid)
  ErrorStats ate_m;                // |p_gt - S_gt_est * p_est| over associated pairs [m]
  RpeResult rpe_per_s;             // delta = options.rpe_delta_s in ground-truth time
  RpeResult rpe_per_m;             // delta = options.rpe_delta_m of travelled ground truth
  ErrorStats frame_to_frame_m;     // between consecutive associated poses, after alignment [m]
  double worst_jump_t_s = 0.0;     // estimate time of the later pose of the worst one [s]
  size_t jumps = 0;                // frame-to-frame errors above options.jump_threshold_m
  std::vector<size_t> jump_pairs;  // each jump's later pose, as an index into 'pairs' 
  std::vector<PosePair> pairs;     // the association, sorted by estimate time
};

// Errors: no pose associated (names max_dt and both time ranges), fewer than 3 associated
// poses or a degenerate alignment, or invalid options (non-positive max_dt or deltas).
Expected<EvalResult> evaluateTrajectory(const Trajectory& groundtruth, const Trajectory& estimate,
                                        const EvalOptions& options);

// The paper's Table I: the error at the end of a run. Both trajectories are expressed
// relative to their first associated pose (the SLAM map starts at the first posed frame),
// and the last associated poses compared: E = (G_0^-1 G_n)^-1 (P_0^-1 P_n), with G ground
// truth and P the estimate, 0 and n the first and last associated pose in time.
struct EndPointError {
  double position_m = 0.0;        // |translation of E| [m]
  double distance_m = 0.0;        // ground truth travelled from pose 0 to pose n [m]
  double position_percent = 0.0;  // 100 position_m / distance_m (0 when distance_m is 0)
  double rotation_deg = 0.0;      // rotation angle of E [deg]
  double first_t = 0.0, last_t = 0.0;  // estimate times of poses 0 and n [s]
};
// Errors: fewer than 2 associated poses (association as associateByTime).
Expected<EndPointError> endPointError(const Trajectory& groundtruth, const Trajectory& estimate,
                                      double max_dt_s);
// "key value" lines: final_position_error_m, final_position_error_percent,
// final_rotation_error_deg, final_distance_m (%.6f).
std::string toKeyValueText(const EndPointError& error);

// JSON object (one line per key) with ate_rmse_m, ate_mean_m, ate_median_m, ate_std_m,
// ate_min_m, ate_max_m, scale, rpe_per_s_* / rpe_per_m_* (trans_rmse_m, rot_rmse_deg, pairs;
// null when no pair spans the delta), num_estimate, num_groundtruth, num_associated,
// num_frames and coverage (null when unknown), alignment ("rigid" / "similarity"), max_dt_s,
// rpe_delta_s, rpe_delta_m, f2f_median_m, f2f_max_m, f2f_max_t_s, jumps, jump_threshold_m,
// and T_gt_est (translation_m, quaternion_xyzw).
std::string toJson(const EvalResult& result);
// The same keys as "key value" lines (values %.6f, counts as integers, "null" when unknown).
std::string toKeyValueText(const EvalResult& result);

// A PNG (1200 x 600): left, a top view of the ground truth and the aligned estimate in the
// ground truth's plane of largest extent (the two axes with the largest ranges; named on the
// plot), equal axis scaling, a scale bar in metres and a legend; right, the remaining axis
// over time for both. The path must end in ".png". Errors: bad extension, write failure.
Status writeTrajectoryPlot(const std::string& png_path, const Trajectory& groundtruth,
                           const Trajectory& estimate, const EvalResult& result);

}  // namespace rgbdslam
