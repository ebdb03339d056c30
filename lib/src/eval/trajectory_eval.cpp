#include "rgbdslam/eval/trajectory_eval.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <sstream>
#include <tuple>
#include <variant>

namespace rgbdslam {
namespace {

// An RPE partner j of i must be at least delta later; these tolerances absorb rounding in
// differences of large timestamps (TUM stamps are ~1.3e9 s, resolution 1e-6 s) and in sums
// of travelled distance, so that a frame exactly delta later is not skipped.
constexpr double kRpeTimeTolerance_s = 1e-6;
constexpr double kRpeDistanceTolerance_m = 1e-9;
constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

std::vector<size_t> indicesSortedByTime(const Trajectory& trajectory) {
  std::vector<size_t> order(trajectory.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return trajectory[a].t < trajectory[b].t; });
  return order;
}

// For each pose k of a non-decreasing key sequence, the first later pose j with
// key[j] - key[k] >= delta - tolerance; pairs (k, j) for which such a j exists.
std::vector<std::pair<size_t, size_t>> pairsAtLeastDeltaApart(const std::vector<double>& key,
                                                              double delta, double tolerance) {
  std::vector<std::pair<size_t, size_t>> pairs;
  size_t j = 0;
  for (size_t i = 0; i < key.size(); ++i) {
    j = std::max(j, i + 1);
    while (j < key.size() && key[j] - key[i] < delta - tolerance) ++j;
    if (j == key.size()) break;  // keys are non-decreasing: no later i finds a partner either
    pairs.emplace_back(i, j);
  }
  return pairs;
}

// Running maximum, so that the key used for RPE pairing never decreases.
std::vector<double> runningMax(std::vector<double> values) {
  for (size_t k = 1; k < values.size(); ++k) values[k] = std::max(values[k], values[k - 1]);
  return values;
}

// Travelled ground-truth distance [m] up to each ground-truth pose, along time order.
std::vector<double> travelledDistance(const Trajectory& groundtruth) {
  std::vector<double> distance(groundtruth.size(), 0.0);
  const std::vector<size_t> order = indicesSortedByTime(groundtruth);
  for (size_t k = 1; k < order.size(); ++k) {
    const Vec3 step =
        groundtruth[order[k]].T_w_c.translation() - groundtruth[order[k - 1]].T_w_c.translation();
    distance[order[k]] = distance[order[k - 1]] + step.norm();
  }
  return distance;
}

RpeResult relativePoseError(const Trajectory& groundtruth, const Trajectory& estimate,
                            const std::vector<PosePair>& pairs, double estimate_scale,
                            const std::vector<double>& key, double delta, double tolerance) {
  std::vector<double> trans_errors;
  std::vector<double> rot_errors;
  for (const auto& [i, j] : pairsAtLeastDeltaApart(key, delta, tolerance)) {
    const SE3& G_w_i = groundtruth[pairs[i].gt_index].T_w_c;
    const SE3& G_w_j = groundtruth[pairs[j].gt_index].T_w_c;
    const SE3& P_w_i = estimate[pairs[i].est_index].T_w_c;
    const SE3& P_w_j = estimate[pairs[j].est_index].T_w_c;
    const SE3 P_w_i_scaled(P_w_i.rotation(), estimate_scale * P_w_i.translation());
    const SE3 P_w_j_scaled(P_w_j.rotation(), estimate_scale * P_w_j.translation());
    const SE3 E = (G_w_i.inverse() * G_w_j).inverse() * (P_w_i_scaled.inverse() * P_w_j_scaled);
    trans_errors.push_back(E.translation().norm());
    rot_errors.push_back(logSO3(E.rotationMatrix()).norm() * kRadToDeg);
  }
  return RpeResult{computeErrorStats(std::move(trans_errors)),
                   computeErrorStats(std::move(rot_errors))};
}

Status validate(const EvalOptions& options) {
  if (!(options.max_dt_s > 0.0)) return Error{"max_dt_s must be positive"};
  if (!(options.rpe_delta_s > 0.0)) return Error{"rpe_delta_s must be positive"};
  if (!(options.rpe_delta_m > 0.0)) return Error{"rpe_delta_m must be positive"};
  if (options.num_frames && *options.num_frames == 0) return Error{"num_frames must be positive"};
  if (!(options.jump_threshold_m > 0.0)) return Error{"jump_threshold_m must be positive"};
  return {};
}

std::string timeRange(const Trajectory& trajectory) {
  if (trajectory.empty()) return "no poses";
  const auto [lo, hi] =
      std::minmax_element(trajectory.begin(), trajectory.end(),
                          [](const TimedPose& a, const TimedPose& b) { return a.t < b.t; });
  char buffer[128];
  std::snprintf(buffer, sizeof(buffer), "%zu poses, t in [%.6f, %.6f] s", trajectory.size(), lo->t,
                hi->t);
  return buffer;
}

// --- output ------------------------------------------------------------------------------

using FieldValue = std::variant<std::monostate, double, size_t, std::string>;  // monostate: null
using Fields = std::vector<std::pair<std::string, FieldValue>>;

FieldValue optionalNumber(bool known, double value) {
  return known ? FieldValue(value) : FieldValue(std::monostate{});
}

Fields summaryFields(const EvalResult& r) {
  const bool has_rpe_s = r.rpe_per_s.trans_m.count > 0;
  const bool has_rpe_m = r.rpe_per_m.trans_m.count > 0;
  return {
      {"alignment",
       std::string(r.alignment == AlignmentKind::kSimilarity ? "similarity" : "rigid")},
      {"scale", r.S_gt_est.scale},
      {"ate_rmse_m", r.ate_m.rmse},
      {"ate_mean_m", r.ate_m.mean},
      {"ate_median_m", r.ate_m.median},
      {"ate_std_m", r.ate_m.stddev},
      {"ate_min_m", r.ate_m.min},
      {"ate_max_m", r.ate_m.max},
      {"rpe_per_s_pairs", r.rpe_per_s.trans_m.count},
      {"rpe_per_s_trans_rmse_m", optionalNumber(has_rpe_s, r.rpe_per_s.trans_m.rmse)},
      {"rpe_per_s_rot_rmse_deg", optionalNumber(has_rpe_s, r.rpe_per_s.rot_deg.rmse)},
      {"rpe_per_m_pairs", r.rpe_per_m.trans_m.count},
      {"rpe_per_m_trans_rmse_m", optionalNumber(has_rpe_m, r.rpe_per_m.trans_m.rmse)},
      {"rpe_per_m_rot_rmse_deg", optionalNumber(has_rpe_m, r.rpe_per_m.rot_deg.rmse)},
      {"num_estimate", r.num_estimate},
      {"num_groundtruth", r.num_groundtruth},
      {"num_associated", r.num_associated},
      {"num_frames",
       r.options.num_frames ? FieldValue(*r.options.num_frames) : FieldValue(std::monostate{})},
      {"coverage", optionalNumber(r.coverage.has_value(), r.coverage.value_or(0.0))},
      {"max_dt_s", r.options.max_dt_s},
      {"rpe_delta_s", r.options.rpe_delta_s},
      {"rpe_delta_m", r.options.rpe_delta_m},
      {"f2f_median_m", r.frame_to_frame_m.median},
      {"f2f_max_m", r.frame_to_frame_m.max},
      {"f2f_max_t_s", r.worst_jump_t_s},
      {"jumps", r.jumps},
      {"jump_threshold_m", r.options.jump_threshold_m},
  };
}

std::string formatDouble(const char* format, double value) {
  if (!std::isfinite(value)) return "null";
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

// format: printf format for doubles; quote: whether strings are quoted (JSON).
std::string formatValue(const FieldValue& value, const char* format, bool quote) {
  if (std::holds_alternative<std::monostate>(value)) return "null";
  if (const double* d = std::get_if<double>(&value)) return formatDouble(format, *d);
  if (const size_t* n = std::get_if<size_t>(&value)) return std::to_string(*n);
  const std::string& s = std::get<std::string>(value);
  return quote ? "\"" + s + "\"" : s;
}

std::string jsonArray(std::initializer_list<double> values) {
  std::string out = "[";
  for (const double v : values) {
    if (out.size() > 1) out += ", ";
    out += formatDouble("%.12g", v);
  }
  return out + "]";
}

}  // namespace

ErrorStats computeErrorStats(std::vector<double> values) {
  ErrorStats stats;
  stats.count = values.size();
  if (values.empty()) return stats;
  std::sort(values.begin(), values.end());
  const double n = static_cast<double>(values.size());
  double sum = 0.0;
  double sum_sq = 0.0;
  for (const double v : values) {
    sum += v;
    sum_sq += v * v;
  }
  stats.mean = sum / n;
  stats.rmse = std::sqrt(sum_sq / n);
  double sum_dev_sq = 0.0;
  for (const double v : values) sum_dev_sq += (v - stats.mean) * (v - stats.mean);
  stats.stddev = std::sqrt(sum_dev_sq / n);
  const size_t mid = values.size() / 2;
  stats.median = values.size() % 2 ? values[mid] : 0.5 * (values[mid - 1] + values[mid]);
  stats.min = values.front();
  stats.max = values.back();
  return stats;
}

std::vector<PosePair> associateByTime(const Trajectory& groundtruth, const Trajectory& estimate,
                                      double max_dt_s) {
  const std::vector<size_t> gt_order = indicesSortedByTime(groundtruth);
  std::vector<double> gt_times(gt_order.size());
  for (size_t k = 0; k < gt_order.size(); ++k) gt_times[k] = groundtruth[gt_order[k]].t;

  std::vector<std::tuple<double, size_t, size_t>> candidates;  // (|dt|, est, gt)
  for (size_t e = 0; e < estimate.size(); ++e) {
    const double t = estimate[e].t;
    auto it = std::lower_bound(gt_times.begin(), gt_times.end(), t - max_dt_s);
    for (; it != gt_times.end() && *it <= t + max_dt_s; ++it) {
      const size_t g = gt_order[static_cast<size_t>(it - gt_times.begin())];
      candidates.emplace_back(std::abs(t - *it), e, g);
    }
  }
  std::sort(candidates.begin(), candidates.end());

  std::vector<bool> est_taken(estimate.size(), false);
  std::vector<bool> gt_taken(groundtruth.size(), false);
  std::vector<PosePair> pairs;
  for (const auto& [abs_dt, e, g] : candidates) {
    if (est_taken[e] || gt_taken[g]) continue;
    est_taken[e] = gt_taken[g] = true;
    pairs.push_back(PosePair{g, e, estimate[e].t - groundtruth[g].t});
  }
  std::sort(pairs.begin(), pairs.end(), [&](const PosePair& a, const PosePair& b) {
    const double ta = estimate[a.est_index].t;
    const double tb = estimate[b.est_index].t;
    return ta != tb ? ta < tb : a.est_index < b.est_index;
  });
  return pairs;
}

Expected<EvalResult> evaluateTrajectory(const Trajectory& groundtruth, const Trajectory& estimate,
                                        const EvalOptions& options) {
  if (Status valid = validate(options); !valid)
    return Error{"evaluateTrajectory: " + valid.error()};
  EvalResult result;
  result.options = options;
  result.alignment = options.similarity ? AlignmentKind::kSimilarity : AlignmentKind::kRigid;
  result.num_estimate = estimate.size();
  result.num_groundtruth = groundtruth.size();
  result.pairs = associateByTime(groundtruth, estimate, options.max_dt_s);
  result.num_associated = result.pairs.size();
  if (options.num_frames) {
    // A fraction of frames: capped at 1 when there are more associated poses than frames
    // (an estimate at a higher rate than the frames, or the ground truth evaluated against itself).
    result.coverage = std::min(
        1.0, static_cast<double>(result.num_associated) / static_cast<double>(*options.num_frames));
  }
  if (result.pairs.empty()) {
    return Error{"no estimated pose lies within max_dt = " + formatDouble("%g", options.max_dt_s) +
                 " s of a ground-truth pose (estimate: " + timeRange(estimate) +
                 "; ground truth: " + timeRange(groundtruth) + ")"};
  }

  // ATE: align the associated estimated positions to the ground-truth positions.
  std::vector<Vec3> p_est;
  std::vector<Vec3> p_gt;
  for (const PosePair& pair : result.pairs) {
    p_est.push_back(estimate[pair.est_index].T_w_c.translation());
    p_gt.push_back(groundtruth[pair.gt_index].T_w_c.translation());
  }
  auto S_gt_est = alignPoints(p_est, p_gt, result.alignment);
  if (!S_gt_est) return Error{"cannot align the estimate to the ground truth: " + S_gt_est.error()};
  result.S_gt_est = *S_gt_est;
  std::vector<double> ate_errors;
  for (size_t k = 0; k < p_est.size(); ++k) {
    ate_errors.push_back((p_gt[k] - result.S_gt_est * p_est[k]).norm());
  }
  result.ate_m = computeErrorStats(std::move(ate_errors));

  // Frame to frame, in the ground truth's world: the aligned step against the true step.
  std::vector<double> steps;
  double worst = -1.0;
  for (size_t k = 1; k < p_est.size(); ++k) {
    const Vec3 step_est = result.S_gt_est * p_est[k] - result.S_gt_est * p_est[k - 1];
    const double error = (step_est - (p_gt[k] - p_gt[k - 1])).norm();
    steps.push_back(error);
    if (error > options.jump_threshold_m) {
      ++result.jumps;
      result.jump_pairs.push_back(k);
    }
    if (error > worst) {
      worst = error;
      result.worst_jump_t_s = estimate[result.pairs[k].est_index].t;
    }
  }
  result.frame_to_frame_m = computeErrorStats(std::move(steps));

  // RPE, keyed by ground-truth time and by travelled ground-truth distance.
  const std::vector<double> distance = travelledDistance(groundtruth);
  std::vector<double> time_key;
  std::vector<double> distance_key;
  for (const PosePair& pair : result.pairs) {
    time_key.push_back(groundtruth[pair.gt_index].t);
    distance_key.push_back(distance[pair.gt_index]);
  }
  const double scale = result.S_gt_est.scale;
  result.rpe_per_s =
      relativePoseError(groundtruth, estimate, result.pairs, scale, runningMax(time_key),
                        options.rpe_delta_s, kRpeTimeTolerance_s);
  result.rpe_per_m =
      relativePoseError(groundtruth, estimate, result.pairs, scale, runningMax(distance_key),
                        options.rpe_delta_m, kRpeDistanceTolerance_m);
  return result;
}

std::string toJson(const EvalResult& result) {
  std::ostringstream out;
  out << "{\n";
  for (const auto& [key, value] : summaryFields(result)) {
    out << "  \"" << key << "\": " << formatValue(value, "%.9g", true) << ",\n";
  }
  const SE3 T_gt_est = result.S_gt_est.rigidPart();
  const Vec3& t = T_gt_est.translation();
  const Eigen::Quaterniond& q = T_gt_est.rotation();
  out << "  \"T_gt_est\": {\"translation_m\": " << jsonArray({t.x(), t.y(), t.z()})
      << ", \"quaternion_xyzw\": " << jsonArray({q.x(), q.y(), q.z(), q.w()}) << "}\n";
  out << "}\n";
  return out.str();
}

std::string toKeyValueText(const EvalResult& result) {
  std::string out;
  for (const auto& [key, value] : summaryFields(result)) {
    out += key + " " + formatValue(value, "%.6f", false) + "\n";
  }
  return out;
}

Expected<EndPointError> endPointError(const Trajectory& groundtruth, const Trajectory& estimate,
                                      double max_dt_s) {
  const std::vector<PosePair> pairs = associateByTime(groundtruth, estimate, max_dt_s);
  if (pairs.size() < 2) {
    return Error{"end-point error needs 2 associated poses, got " + std::to_string(pairs.size())};
  }
  const PosePair& first = pairs.front();
  const PosePair& last = pairs.back();  // pairs are sorted by estimate time
  const SE3 gt_motion =
      groundtruth[first.gt_index].T_w_c.inverse() * groundtruth[last.gt_index].T_w_c;
  const SE3 est_motion = estimate[first.est_index].T_w_c.inverse() * estimate[last.est_index].T_w_c;
  const SE3 error = gt_motion.inverse() * est_motion;
  const std::vector<double> travelled = travelledDistance(groundtruth);
  EndPointError e;
  e.position_m = error.translation().norm();
  e.distance_m = travelled[last.gt_index] - travelled[first.gt_index];
  e.position_percent = e.distance_m > 0.0 ? 100.0 * e.position_m / e.distance_m : 0.0;
  e.rotation_deg = logSO3(error.rotationMatrix()).norm() * kRadToDeg;
  e.first_t = estimate[first.est_index].t;
  e.last_t = estimate[last.est_index].t;
  return e;
}

std::string toKeyValueText(const EndPointError& error) {
  char text[256];
  std::snprintf(text, sizeof(text),
                "final_position_error_m %.6f\nfinal_position_error_percent %.6f\n"
                "final_rotation_error_deg %.6f\nfinal_distance_m %.6f\n",
                error.position_m, error.position_percent, error.rotation_deg, error.distance_m);
  return text;
}

}  // namespace rgbdslam
