#include "rgbdslam/mapping/place_recognition.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

namespace rgbdslam {
namespace {

double angleDegOf(const SE3& T) { return T.rotation().angularDistance(Eigen::Quaterniond::Identity()) * 180.0 / M_PI; }

// Two poses of one camera further apart than the given translation or rotation.
bool posesDisagree(const SE3& a, const SE3& b, double max_m, double max_deg) {
  const SE3 delta = a.inverse() * b;
  return delta.translation().norm() > max_m || angleDegOf(delta) > max_deg;
}

// The noise of one reading at p (camera frame): depth_sigma along the ray, lateral_sigma
// across it [m^2].
Mat3 readingCovariance(const Vec3& p, double depth_sigma, double lateral_sigma) {
  const Vec3 ray = p.normalized();
  const double l2 = lateral_sigma * lateral_sigma;
  return l2 * Mat3::Identity() + (depth_sigma * depth_sigma - l2) * ray * ray.transpose();
}

}  // namespace

// The information of the inliers' 3-D agreement about the query pose, perturbed in its own
// frame (T_k_q * exp(delta)): residual r = p_q + dt + dw x p_q - T_q_k p_k, J = [I, -[p_q]x],
// with both readings' noise (the keyframe's turned into the query's frame).
PoseSigma poseSigmaOf(const Features3d& query, const Features3d& keyframe, const SE3& T_k_q,
                      const std::vector<std::pair<int, int>>& inliers, const NoiseModel& noise,
                      double lateral_sigma_px, double focal_px) {
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  const Mat3 R_q_k = T_k_q.rotationMatrix().transpose();
  for (const auto& [qi, ki] : inliers) {
    const Vec3 p_q = query.p[static_cast<size_t>(qi)].cast<double>();
    const Vec3 p_k = keyframe.p[static_cast<size_t>(ki)].cast<double>();
    const Mat3 covariance =
        readingCovariance(p_q, noise.sigmaDepth(p_q.z()), p_q.z() * lateral_sigma_px / focal_px) +
        R_q_k * readingCovariance(p_k, noise.sigmaDepth(p_k.z()), p_k.z() * lateral_sigma_px / focal_px) * R_q_k.transpose();
    Eigen::Matrix<double, 3, 6> J;
    J << Mat3::Identity(), -skew(p_q);
    information += J.transpose() * covariance.inverse() * J;
  }
  const Eigen::Matrix<double, 6, 6> pose_covariance = information.inverse();
  if (!pose_covariance.allFinite()) return {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  Eigen::SelfAdjointEigenSolver<Mat3> t(pose_covariance.topLeftCorner<3, 3>()), w(pose_covariance.bottomRightCorner<3, 3>());
  return {std::sqrt(std::max(0.0, t.eigenvalues().maxCoeff())),
          std::sqrt(std::max(0.0, w.eigenvalues().maxCoeff())) * 180.0 / M_PI};
}

void PlaceRecognitionOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "candidates", &candidates, 1, 100, "keyframes", "keyframes verified at most, best appearance first");
  r->bind(s, "min_score_ratio", &min_score_ratio, 0.0, 1.0, "",
          "a candidate scores at least this fraction of the best bag-of-words score");
  r->bind(s, "match_ratio", &match_ratio, 0.1, 1.0, "", "Lowe's ratio test of the ORB matches");
  r->bind(s, "ransac_iterations", &ransac_iterations, 1, 100000, "samples", "3-point RANSAC samples");
  r->bind(s, "inlier_sigmas", &inlier_sigmas, 0.5, 100.0, "sigmas",
          "a 3-D match agrees within this many sigmas of both readings' depth noise");
  r->bind(s, "inlier_min_m", &inlier_min_m, 0.0, 1.0, "m", "...and at least within this");
  r->bind(s, "min_inliers", &min_inliers, 3, 100000, "matches", "a verified candidate has at least this many inliers");
  r->bind(s, "min_inlier_fraction", &min_inlier_fraction, 0.0, 1.0, "",
          "...that are at least this fraction of its matches");
  r->bind(s, "lateral_sigma_px", &lateral_sigma_px, 0.1, 100.0, "px",
          "position noise of an ORB feature across its ray, for the pose's uncertainty");
  r->bind(s, "max_sigma_m", &max_sigma_m, 0.0, 10.0, "m",
          "a verified pose is known to 1 sigma within this (largest axis)...");
  r->bind(s, "max_sigma_deg", &max_sigma_deg, 0.0, 180.0, "deg", "...and within this in rotation");
  r->bind(s, "ambiguity_m", &ambiguity_m, 0.0, 100.0, "m",
          "verified poses of one query further apart: ambiguous, refused");
  r->bind(s, "ambiguity_deg", &ambiguity_deg, 0.0, 180.0, "deg", "...or turned further apart");
  r->bind(s, "drift_min_m", &drift_min_m, 0.0, 1000.0, "m", "loop correction allowed after no path");
  r->bind(s, "drift_fraction", &drift_fraction, 0.0, 1.0, "",
          "...plus this fraction of the path flown since the keyframe");
  r->bind(s, "drift_min_deg", &drift_min_deg, 0.0, 180.0, "deg", "rotation correction allowed after no path");
  r->bind(s, "drift_deg_per_m", &drift_deg_per_m, 0.0, 180.0, "deg/m", "...plus this much per metre of path");
  pose.noise.bind(r);  // the pose refinement itself keeps its defaults
}

const char* toString(PlaceStatus status) {
  switch (status) {
    case PlaceStatus::kRecognised: return "recognised";
    case PlaceStatus::kNoFeatures: return "no features";
    case PlaceStatus::kNoCandidate: return "no candidate";
    case PlaceStatus::kNotVerified: return "not verified";
    case PlaceStatus::kInconsistentWithOdometry: return "inconsistent with odometry";
    case PlaceStatus::kAmbiguous: return "ambiguous";
  }
  return "?";
}

bool PlaceExclusion::excludes(KeyframeId id) const {
  return id > newest || std::find(ids.begin(), ids.end(), id) != ids.end();
}

PlaceDatabase::PlaceDatabase(const PinholeCamera& camera, const PlaceRecognitionOptions& options,
                             const BinaryVocabulary* vocabulary)
    : camera_(camera), options_(options), vocabulary_(vocabulary ? vocabulary : &projectVocabulary()) {}

void PlaceDatabase::add(KeyframeId id, const SE3& T_w_k, Features3d features) {
  assert(entries_.empty() || id > entries_.back().id);
  Entry entry;
  entry.id = id;
  entry.T_w_k = T_w_k;
  const BowVector bag = vocabulary_->bag(features.descriptors);
  entry.features = std::move(features);
  if (!entries_.empty()) {
    const Entry& last = entries_.back();
    entry.path_m = last.path_m + (T_w_k.translation() - last.T_w_k.translation()).norm();
  }
  index_.add(static_cast<int>(entries_.size()), bag);
  entries_.push_back(std::move(entry));
}

bool PlaceDatabase::setPose(KeyframeId id, const SE3& T_w_k) {
  const Entry* entry = find(id);
  if (!entry) return false;
  entries_[static_cast<size_t>(entry - entries_.data())].T_w_k = T_w_k;
  return true;
}

bool PlaceDatabase::remove(KeyframeId id) {
  const Entry* found = find(id);
  if (!found) return false;
  const int index = static_cast<int>(found - entries_.data());
  index_.remove(index);
  entries_[static_cast<size_t>(index)].features = Features3d{};
  return true;
}

const PlaceDatabase::Entry* PlaceDatabase::find(KeyframeId id) const {
  const auto it = std::lower_bound(entries_.begin(), entries_.end(), id,
                                   [](const Entry& e, KeyframeId key) { return e.id < key; });
  return it != entries_.end() && it->id == id ? &*it : nullptr;
}

std::vector<PlaceCandidate> PlaceDatabase::query(const Features3d& features, const PlaceExclusion& exclusion) const {
  // Entries are the index's images; their ids increase with them, so ties still go to the older.
  const std::vector<BowIndex::Hit> hits =
      index_.query(vocabulary_->bag(features.descriptors), static_cast<size_t>(options_.candidates),
                   [&](int entry) { return exclusion.excludes(entries_[static_cast<size_t>(entry)].id); });
  std::vector<PlaceCandidate> ranked;
  for (const BowIndex::Hit& hit : hits) ranked.push_back({entries_[static_cast<size_t>(hit.image)].id, hit.score});
  if (!ranked.empty()) {
    const double floor = options_.min_score_ratio * ranked.front().score;
    ranked.erase(std::remove_if(ranked.begin(), ranked.end(), [floor](const PlaceCandidate& c) { return c.score < floor; }),
                 ranked.end());
  }
  return ranked;
}

bool PlaceDatabase::withinDrift(const Entry& keyframe, const SE3& T_w_q_estimate, const SE3& T_w_q) const {
  const Entry& last = entries_.back();
  const double path_q = last.path_m + (T_w_q_estimate.translation() - last.T_w_k.translation()).norm();
  const double path_m = std::max(0.0, path_q - keyframe.path_m);
  return !posesDisagree(T_w_q_estimate, T_w_q, options_.drift_min_m + options_.drift_fraction * path_m,
                        options_.drift_min_deg + options_.drift_deg_per_m * path_m);
}

PlaceMatch PlaceDatabase::verify(const Features3d& features, const std::vector<PlaceCandidate>& candidates,
                                 const std::optional<SE3>& T_w_q_estimate, const Plausible& plausible) const {
  const auto consistent_with = [&](const Entry& keyframe, const SE3& T_w_q) {
    return (!T_w_q_estimate || withinDrift(keyframe, *T_w_q_estimate, T_w_q)) && (!plausible || plausible(keyframe.id, T_w_q));
  };
  PlaceMatch match;
  match.candidates = candidates;
  if (features.size() < 3) {
    match.status = PlaceStatus::kNoFeatures;
    return match;
  }
  if (candidates.empty()) {
    match.status = PlaceStatus::kNoCandidate;
    return match;
  }
  FeatureRelocaliserOptions geometry;
  geometry.ratio = options_.match_ratio;
  geometry.ransac_iterations = options_.ransac_iterations;
  geometry.inlier_sigmas = options_.inlier_sigmas;
  geometry.inlier_min_m = options_.inlier_min_m;
  geometry.min_inliers = options_.min_inliers;
  std::vector<const Entry*> keyframe_of;
  std::vector<SE3> consistent_poses;      // verified and within the drift bound, so far...
  std::vector<SE3> consistent_keyframes;  // ...and the poses of their keyframes
  for (const PlaceCandidate& candidate : candidates) {
    const Entry* keyframe = find(candidate.keyframe);
    if (!keyframe) continue;
    // A keyframe within the ambiguity bound of one already verified sees the same place from
    // the same view: it would give the same pose, so it is not verified again (~5 ms each;
    // the same place seen again and again, e.g. hovering, took 10 verifications).
    const bool same_view = std::any_of(consistent_keyframes.begin(), consistent_keyframes.end(), [&](const SE3& other) {
      return !posesDisagree(other, keyframe->T_w_k, options_.ambiguity_m, options_.ambiguity_deg);
    });
    if (same_view) continue;
    const auto pose = poseFromFeatures(features, keyframe->features, keyframe->T_w_k, camera_, options_.pose, geometry);
    if (!pose || pose->inliers < options_.min_inlier_fraction * pose->matches) continue;
    const SE3 T_k_q = keyframe->T_w_k.inverse() * pose->T_w_c;
    const PoseSigma sigma = poseSigmaOf(features, keyframe->features, T_k_q, pose->inlier_matches, options_.pose.noise,
                                        options_.lateral_sigma_px, camera_.fx);
    if (sigma.translation_m > options_.max_sigma_m || sigma.rotation_deg > options_.max_sigma_deg) continue;
    match.verified.push_back({keyframe->id, T_k_q, pose->T_w_c, pose->matches, pose->inliers, sigma});
    keyframe_of.push_back(keyframe);
    // Two consistent poses more than twice the ambiguity bound apart: whichever turns out
    // best, one of them disagrees with it (triangle inequality), so the verdict is
    // kAmbiguous already and the other candidates need no verification (~5 ms each).
    if (!consistent_with(*keyframe, pose->T_w_c)) continue;
    const bool ambiguous = std::any_of(consistent_poses.begin(), consistent_poses.end(), [&](const SE3& other) {
      return posesDisagree(other, pose->T_w_c, 2.0 * options_.ambiguity_m, 2.0 * options_.ambiguity_deg);
    });
    if (ambiguous) break;
    consistent_poses.push_back(pose->T_w_c);
    consistent_keyframes.push_back(keyframe->T_w_k);
  }
  if (match.verified.empty()) {
    match.status = PlaceStatus::kNotVerified;
    return match;
  }
  auto most_inliers = [](const PlaceVerification& a, const PlaceVerification& b) { return a.inliers < b.inliers; };
  match.best = *std::max_element(match.verified.begin(), match.verified.end(), most_inliers);
  // Odometry: only the verified poses within the drift bound of the estimate stay.
  std::vector<PlaceVerification> consistent;
  for (size_t i = 0; i < match.verified.size(); ++i) {
    if (consistent_with(*keyframe_of[i], match.verified[i].T_w_q)) {
      consistent.push_back(match.verified[i]);
    }
  }
  if (consistent.empty()) {
    match.status = PlaceStatus::kInconsistentWithOdometry;
    return match;
  }
  match.best = *std::max_element(consistent.begin(), consistent.end(), most_inliers);
  // Ambiguity: every remaining verified pose must agree with the best one.
  for (const PlaceVerification& v : consistent) {
    if (posesDisagree(v.T_w_q, match.best.T_w_q, options_.ambiguity_m, options_.ambiguity_deg)) {
      match.status = PlaceStatus::kAmbiguous;
      return match;
    }
  }
  match.status = PlaceStatus::kRecognised;
  return match;
}

PlaceMatch PlaceDatabase::recognise(const Features3d& features, const PlaceExclusion& exclusion,
                                    const std::optional<SE3>& T_w_q_estimate) const {
  if (features.size() < 3) {
    PlaceMatch match;
    match.status = PlaceStatus::kNoFeatures;
    return match;
  }
  return verify(features, query(features, exclusion), T_w_q_estimate);
}

}  // namespace rgbdslam
