#pragma once
// Loop closures checked against ground truth (issue 11: "wrong closures: 0"). A recognised
// place gives a loop edge, the new keyframe's pose in the recognised keyframe's frame as the
// verification measured it (mapping/loop_closer.h, LoopClosureResult::T_with_query). Relative
// poses do not depend on the world frame, so the edge compares directly with the truth's
// G_with^-1 G_query at the two keyframes' times, without any alignment.
//
// A wrong edge (perceptual aliasing: a lookalike place taken for the one seen before, or a
// verification locked onto repeated structure) is off by the distance between the two places
// it confuses: 14 m between the lookalike rooms of synth:twins, a metre or more between a
// door or a shelf and its repeat along a wall. A right edge is off by what depth noise and
// feature positions leave in a 3-D-3-D fit, centimetres and a fraction of a degree (the
// worst right edge is printed beside the count, so each run shows its distance from the
// bar). The bar, 0.25 m or 5 deg, only names which side an edge is on; no run's figure set it.
//
// Call order: auditLoops(truth, results, options) -> LoopAudit; toKeyValueText(audit).
#include <string>
#include <vector>

#include "rgbdslam/io/trajectory_io.h"
#include "rgbdslam/mapping/loop_closer.h"

namespace rgbdslam {

struct LoopAuditOptions {
  double wrong_m = 0.25;    // an edge off the truth by more than this is wrong [m]...
  double wrong_deg = 5.0;   // ...or turned off it by more than this [deg]
  double max_dt_s = 0.02;   // a keyframe's time matches a truth pose within this [s]
};

struct LoopAudit {
  long checked = 0;     // recognised places with a truth pose at both keyframes' times
  long unmatched = 0;   // ...without one (not checked)
  // Accepted: closed, agreed with the map, joined two parts, or below min_correction; each
  // of these is in the map's pose graph. Refused: the graph refused the edge (nothing moved).
  long accepted = 0, accepted_wrong = 0;
  long refused = 0, refused_wrong = 0;
  double accepted_max_error_m = 0.0, accepted_max_error_deg = 0.0;  // over the accepted edges
  double right_max_error_m = 0.0, right_max_error_deg = 0.0;        // over every right edge
};

// The edge's error against the truth: translation [m] and rotation [deg] of
// (G_a^-1 G_b)^-1 T_a_b; false when either time has no truth pose within max_dt_s.
bool loopEdgeError(const Trajectory& truth, int64_t utime_a, int64_t utime_b, const SE3& T_a_b,
                   double max_dt_s, double* error_m, double* error_deg);

LoopAudit auditLoops(const Trajectory& truth, const std::vector<LoopClosureResult>& recognised,
                     const LoopAuditOptions& options = {});

// "key value" lines: loop_audit_checked, loop_audit_unmatched, loops_accepted,
// loops_accepted_wrong, loops_refused_checked, loops_refused_wrong, loop_accepted_max_error_m /
// _deg, loop_right_max_error_m / _deg, loop_wrong_bar_m / _deg.
std::string toKeyValueText(const LoopAudit& audit, const LoopAuditOptions& options);

}  // namespace rgbdslam
