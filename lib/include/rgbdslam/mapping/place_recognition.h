#pragma once
// Place recognition over all keyframes, verified with depth (issue 11, item 1): the ground
// mapper's way to notice that the camera is back at a place it mapped long ago (a loop to
// close), or where a lost camera is (relocalisation from anywhere). Called by the loop
// closer (loop_closer.h) on every new keyframe.
//
// Call order: PlaceDatabase db(camera, options); db.add(id, T_w_k, features) for every
// keyframe, ids increasing (features: extractFeatures3d of the keyframe, as the tracker keeps
// them); db.setPose(id, T_w_k) when bundle adjustment or a loop closure moves a keyframe;
// for a new keyframe or a lost frame: db.recognise(features, exclusion, T_w_q estimate) =
// db.query() (candidates by appearance) then db.verify() (geometry with depth).
//
// Appearance: a bag of binary words (binary_vocabulary.h; 982 words of ORB descriptors,
// trained from the project's own rendered corridor and office at first use, 1.9 s), tf-idf
// scored through an inverted index over all keyframes. Decision, measured on synth:flight
// (3 min, a keyframe every 10 frames: 540; `bench_place_recognition --measure`; docs/design.md,
// "Place recognition"): of the 240 keyframes that see again (half their features) a place
// mapped 100+ frames before, the bag ranks a keyframe of that place first for 43 % and within
// the best 5 for 58 %; small blurry images (PTAM's, ZMSSD over all keyframes) 32 % and 44 %:
// they need the same viewpoint, while the flight re-enters its rooms through other doors. The
// bag costs 0.33 ms per query against 1000 keyframes, the SBI ranking 1.7 ms.
//
// Verification: ORB matches with the candidate keyframe (ratio test), 3-point RANSAC on the
// matched 3-D points and the refined pose (poseFromFeatures, feature_relocaliser.h); a
// candidate is verified with at least min_inliers inliers that are min_inlier_fraction of
// the matches, and only if they fix the pose well: its 1-sigma uncertainty from the inliers'
// depth noise (poseSigmaOf) within max_sigma_m and max_sigma_deg. (Measured on the flight:
// every verified candidate was the right place, but far points on one wall left poses 5-43 cm
// off, with sigmas of 2-16 cm; the error stays within ~3 sigma.) Then, against perceptual
// aliasing (two places that look alike: no appearance or geometry test tells identical rooms
// apart):
//  - odometry: given the query's estimated pose, a verified pose that moves it further than
//    the drift since the candidate keyframe could explain (drift_min + drift_fraction * path
//    length through the keyframes since that one) is refused (kInconsistentWithOdometry);
//  - ambiguity: verified candidates that put the query at incompatible poses (more than
//    ambiguity_m / ambiguity_deg apart) are refused (kAmbiguous), whichever is right.
// What this cannot refuse: a first visit to an exact twin of a mapped place that lies within
// the drift bound of it (a long flight makes the bound large). Tests: a twin of the room
// 10 m away on a first and on a second visit; the room with other paint (same geometry).
// Result on the flight with the defaults: 37 places recognised, 36 within 5 cm and 2 deg of
// the truth and 1 at 5.8 cm (all the right place: precision 100 % by place, 97 % by pose);
// recall 15 % of the 240 revisiting keyframes (86 of 540 keyframes have no features with
// depth: the hall's walls lie beyond the depth range).
//
// Frames: T_w_k keyframe to world, T_w_q the query camera to world, T_k_q query to keyframe.
// Memory: grows with the run by each keyframe's features (52 bytes each, <= 26 kB) and bag
// (8 bytes a word, <= 4 kB): <= 30 kB a keyframe, 30 MB for 1000 keyframes.
// Time per recognise() (bench_place_recognition): the bag's query 0.26 / 0.33 ms against
// 100 / 1000 keyframes; the verification ~1.5 ms per candidate that fails and ~5 ms per one
// that verifies, so 15 ms per keyframe on average over the flight. Verification stops early
// (same verdict): once two consistent poses are more than twice the ambiguity bound apart
// (kAmbiguous whichever is best), and a candidate whose keyframe lies within the ambiguity
// bound of one verified already is not verified again (the same view gives the same pose).
// Benchmark (2026-11-24, one core): 10 candidates, copies of each place 50 m apart (before
// the early stops 54 / 72 ms at 100 / 1000 keyframes) 12.8 / 14.6 ms; copies at one pose
// (all agree: the worst case now) 24.9 / 7.6 ms. Targets 20 / 200 ms: the worst case at
// 100 keyframes (10 neighbouring places that all verify) is 25 % over.
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/geometry/se3.h"
#include "rgbdslam/map/map_types.h"
#include "rgbdslam/mapping/binary_vocabulary.h"
#include "rgbdslam/tracking/feature_relocaliser.h"
#include "rgbdslam/tracking/pose_optimizer.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct PlaceRecognitionOptions {
  int candidates = 10;              // keyframes verified at most, best appearance score first
  double min_score_ratio = 0.3;     // ...scoring at least this fraction of the best score
  double match_ratio = 0.8;         // Lowe's ratio test of the ORB matches
  int ransac_iterations = 300;      // 3-point RANSAC samples
  double inlier_sigmas = 3.0;       // a 3-D match agrees within this many depth sigmas
  double inlier_min_m = 0.01;       // ...and at least within this [m]
  int min_inliers = 30;             // a verified candidate has at least this many inliers
  double min_inlier_fraction = 0.2; // ...that are at least this fraction of the matches
  double lateral_sigma_px = 1.5;    // an ORB feature's position noise across its ray [px]
  double max_sigma_m = 0.02;        // a verified pose's 1-sigma uncertainty at most [m]...
  double max_sigma_deg = 0.5;       // ...and in rotation [deg] (largest axis of each)
  double ambiguity_m = 0.2;         // verified poses of one query further apart [m]...
  double ambiguity_deg = 5.0;       // ...or turned further [deg]: ambiguous, refused
  double drift_min_m = 0.3;         // the loop correction allowed after no path [m]
  double drift_fraction = 0.05;     // ...plus this fraction of the path since the keyframe
  double drift_min_deg = 5.0;       // the rotation allowed after no path [deg]
  double drift_deg_per_m = 0.5;     // ...plus this much per metre of path [deg/m]
  PoseOptimizerOptions pose;        // the pose refinement; only its noise model is bound
                                    // (section "noise")

  void bind(OptionRegistry* registry, const std::string& section);
};

enum class PlaceStatus {
  kRecognised,                // one place, verified, consistent
  kNoFeatures,                // the query has no features with depth: nothing to verify
  kNoCandidate,               // no keyframe shares its words (or the database is empty)
  kNotVerified,               // candidates, but none passed the geometric verification
  kInconsistentWithOdometry,  // verified, but further from the estimate than drift explains
  kAmbiguous,                 // verified candidates disagree on where the query is
};
const char* toString(PlaceStatus status);

struct PlaceCandidate {
  KeyframeId keyframe = -1;
  double score = 0.0;  // bag-of-words similarity in [0, 1]
};

// The 1-sigma uncertainty of a verified pose (largest axis), from its inliers' depth noise.
struct PoseSigma {
  double translation_m = 0.0;
  double rotation_deg = 0.0;
};

struct PlaceVerification {
  KeyframeId keyframe = -1;
  SE3 T_k_q;        // the query in the keyframe's frame
  SE3 T_w_q;        // the query in the world (through the keyframe's pose)
  int matches = 0;  // ORB matches after the ratio test
  int inliers = 0;  // of them agreeing in 3-D with the pose
  PoseSigma sigma;  // how well the inliers fix the pose, in the query's frame
};

// The pose uncertainty that the inlier pairs (query feature, keyframe feature) of a fit
// T_k_q give: each reading with its depth noise along its ray and z * lateral_sigma_px /
// focal_px across it. Far points on one plane leave sideways motion and turning nearly
// interchangeable: that shows here as a large sigma.
PoseSigma poseSigmaOf(const Features3d& query, const Features3d& keyframe, const SE3& T_k_q,
                      const std::vector<std::pair<int, int>>& inliers, const NoiseModel& noise,
                      double lateral_sigma_px, double focal_px);

struct PlaceMatch {
  PlaceStatus status = PlaceStatus::kNoCandidate;
  PlaceVerification best;                   // the place when kRecognised (most inliers)
  std::vector<PlaceCandidate> candidates;   // by appearance, best first
  std::vector<PlaceVerification> verified;  // candidates that passed the geometry
  bool recognised() const { return status == PlaceStatus::kRecognised; }
};

// Keyframes that may not be returned: those newer than 'newest' (the recent window: they
// see the same place without a loop) and the listed ones (e.g. the query's neighbours).
struct PlaceExclusion {
  KeyframeId newest = std::numeric_limits<KeyframeId>::max();
  std::vector<KeyframeId> ids;
  bool excludes(KeyframeId id) const;
};

class PlaceDatabase {
 public:
  // 'vocabulary' must outlive the database; nullptr: projectVocabulary().
  PlaceDatabase(const PinholeCamera& camera, const PlaceRecognitionOptions& options,
                const BinaryVocabulary* vocabulary = nullptr);

  // Ids must increase. A keyframe without features (no depth) is kept but never a candidate.
  void add(KeyframeId id, const SE3& T_w_k, Features3d features);
  // Moves a keyframe (after bundle adjustment or a loop closure). False if it is unknown.
  bool setPose(KeyframeId id, const SE3& T_w_k);
  // A keyframe culled from the map: never a candidate again; its features and words are
  // freed (its entry stays, a pose and the path length to it). False if it is unknown.
  bool remove(KeyframeId id);
  size_t size() const { return entries_.size(); }

  // Keyframes by appearance, best first: at most options.candidates, each scoring at least
  // min_score_ratio of the best.
  std::vector<PlaceCandidate> query(const Features3d& features, const PlaceExclusion& exclusion) const;
  // Whether a verified pose of the query (through the keyframe named) is possible at all, as
  // the odometry check is (kInconsistentWithOdometry when none is): the loop closer's bound
  // on joining parts of the map (loop_closer.h).
  using Plausible = std::function<bool(KeyframeId keyframe, const SE3& T_w_q)>;
  // The geometric verification of 'candidates' (see above). T_w_q_estimate: the query's pose
  // as odometry has it, for the drift check; nullopt (relocalisation) skips that check.
  PlaceMatch verify(const Features3d& features, const std::vector<PlaceCandidate>& candidates,
                    const std::optional<SE3>& T_w_q_estimate, const Plausible& plausible = {}) const;
  // query() then verify().
  PlaceMatch recognise(const Features3d& features, const PlaceExclusion& exclusion,
                       const std::optional<SE3>& T_w_q_estimate) const;

 private:
  struct Entry {
    KeyframeId id = -1;
    SE3 T_w_k;
    Features3d features;
    double path_m = 0.0;  // length of the path through the keyframes added up to this one
  };
  PinholeCamera camera_;
  PlaceRecognitionOptions options_;
  const BinaryVocabulary* vocabulary_;
  std::vector<Entry> entries_;
  BowIndex index_;              // the entries' bags (images: indices into entries_)

  const Entry* find(KeyframeId id) const;
  bool withinDrift(const Entry& keyframe, const SE3& T_w_q_estimate, const SE3& T_w_q) const;
};

}  // namespace rgbdslam
