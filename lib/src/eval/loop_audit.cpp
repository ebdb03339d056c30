#include "rgbdslam/eval/loop_audit.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace rgbdslam {
namespace {

// The truth pose nearest to 't' within max_dt_s in a trajectory sorted by time, or null.
const TimedPose* nearestInTime(const Trajectory& sorted, double t, double max_dt_s) {
  const auto after = std::lower_bound(sorted.begin(), sorted.end(), t,
                                      [](const TimedPose& p, double time) { return p.t < time; });
  const TimedPose* best = nullptr;
  if (after != sorted.end()) best = &*after;
  if (after != sorted.begin() && (!best || t - std::prev(after)->t < best->t - t)) best = &*std::prev(after);
  return best && std::abs(best->t - t) <= max_dt_s ? best : nullptr;
}

bool edgeError(const Trajectory& sorted, int64_t utime_a, int64_t utime_b, const SE3& T_a_b, double max_dt_s,
               double* error_m, double* error_deg) {
  const TimedPose* a = nearestInTime(sorted, static_cast<double>(utime_a) * 1e-6, max_dt_s);
  const TimedPose* b = nearestInTime(sorted, static_cast<double>(utime_b) * 1e-6, max_dt_s);
  if (!a || !b) return false;
  const SE3 error = (a->T_w_c.inverse() * b->T_w_c).inverse() * T_a_b;
  *error_m = error.translation().norm();
  *error_deg = error.log().tail<3>().norm() * 180.0 / M_PI;
  return true;
}

Trajectory sortedByTime(Trajectory truth) {
  std::stable_sort(truth.begin(), truth.end(), [](const TimedPose& x, const TimedPose& y) { return x.t < y.t; });
  return truth;
}

}  // namespace

bool loopEdgeError(const Trajectory& truth, int64_t utime_a, int64_t utime_b, const SE3& T_a_b, double max_dt_s,
                   double* error_m, double* error_deg) {
  return edgeError(sortedByTime(truth), utime_a, utime_b, T_a_b, max_dt_s, error_m, error_deg);
}

LoopAudit auditLoops(const Trajectory& truth, const std::vector<LoopClosureResult>& recognised,
                     const LoopAuditOptions& options) {
  const Trajectory sorted = sortedByTime(truth);
  LoopAudit audit;
  for (const LoopClosureResult& r : recognised) {
    double m = 0.0, deg = 0.0;
    if (!edgeError(sorted, r.with_utime, r.query_utime, r.T_with_query, options.max_dt_s, &m, &deg)) {
      ++audit.unmatched;
      continue;
    }
    ++audit.checked;
    const bool wrong = m > options.wrong_m || deg > options.wrong_deg;
    if (!wrong) {
      audit.right_max_error_m = std::max(audit.right_max_error_m, m);
      audit.right_max_error_deg = std::max(audit.right_max_error_deg, deg);
    }
    if (r.refused) {
      ++audit.refused;
      if (wrong) ++audit.refused_wrong;
      continue;
    }
    ++audit.accepted;
    if (wrong) ++audit.accepted_wrong;
    audit.accepted_max_error_m = std::max(audit.accepted_max_error_m, m);
    audit.accepted_max_error_deg = std::max(audit.accepted_max_error_deg, deg);
  }
  return audit;
}

std::string toKeyValueText(const LoopAudit& a, const LoopAuditOptions& options) {
  char text[768];
  std::snprintf(text, sizeof text,
                "loop_audit_checked %ld\nloop_audit_unmatched %ld\nloops_accepted %ld\nloops_accepted_wrong %ld\n"
                "loops_refused_checked %ld\nloops_refused_wrong %ld\nloop_accepted_max_error_m %.6f\n"
                "loop_accepted_max_error_deg %.6f\nloop_right_max_error_m %.6f\nloop_right_max_error_deg %.6f\n"
                "loop_wrong_bar_m %.6f\nloop_wrong_bar_deg %.6f\n",
                a.checked, a.unmatched, a.accepted, a.accepted_wrong, a.refused, a.refused_wrong,
                a.accepted_max_error_m, a.accepted_max_error_deg, a.right_max_error_m, a.right_max_error_deg,
                options.wrong_m, options.wrong_deg);
  return text;
}

}  // namespace rgbdslam
