#include "rgbdslam/tracking/tracker.h"
#include "rgbdslam/tracking/depth_alignment.h"
#include "rgbdslam/tracking/depth_dead_reckoning.h"
#include "rgbdslam/tracking/depth_integrity.h"
#include "rgbdslam/tracking/photometric_integrity.h"
#include "rgbdslam/tracking/feature_relocaliser.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstring>
#include <deque>
#include <future>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <random>
#include <unordered_map>
#include <unordered_set>

#include "rgbdslam/image/corners.h"
#include "rgbdslam/image/small_blurry_image.h"
#include "rgbdslam/mapping/binary_vocabulary.h"
#include "rgbdslam/tracking/keyframe_policy.h"
#include "rgbdslam/tracking/map_replica.h"
#include "rgbdslam/tracking/point_projection.h"
#include "rgbdslam/tracking/pose_optimizer.h"
#include "rgbdslam/tracking/relocaliser.h"
#include "rgbdslam/util/background_worker.h"

namespace rgbdslam {
namespace {

using TrackStatus = TrackResult::Status;

// Both integrity checks of one pose; the reason names the checks that refused it.
struct PoseIntegrity {
  PhotometricIntegrity image;
  DepthIntegrity depth;
  bool consistent() const { return image.consistent && depth.consistent; }
  std::string describe() const {
    std::string reason;
    if (!image.consistent) reason = "the image disagrees with the pose: " + image.describe();
    if (!depth.consistent) {
      reason += (reason.empty() ? "" : "; ") + std::string("depth disagrees with the pose: ") + depth.describe();
    }
    return reason;
  }
};

// The result of tracking one frame from a start pose.
struct Attempt {
  SE3 T_c_w;
  int searched = 0;
  int found = 0;
  double quality = 0.0;
  double median_depth_m = 0.0;  // of the found inliers
  bool did_coarse = false;      // the coarse stage ran
  PoseUncertainty uncertainty;  // of the fine stage's pose (infinite when it failed)
  Mat6 information = Mat6::Zero();  // the measurements' J^T W J it comes from (motion_prior.h)
  bool depth_aided = false;     // the pose fit included point-to-plane against depth
};

// What a keyframe leaves the tracker besides its pyramid, in depth modes (sizes at 640x480).
struct KeyframeExtras {
  std::vector<SurfaceSample> surface;  // depth-aided tracking: 32 bytes a sample, at most 1200 (38 kB)
  Features3d features;                 // relocalisation: 52 bytes a feature, at most 500 (26 kB)
  // The features' bag of words, made with them once the vocabulary is trained (else when
  // the keyframe is indexed); not stored with cold extras (the index holds it).
  std::optional<BowVector> bag;
};

// A cold keyframe's extras in the keyframe store: "RGX1", the sample and feature counts
// (uint32), then the samples, the features' points, pixels and 32-byte descriptors, each
// as this process holds them (the store's file dies with the process).
constexpr char kExtrasMagic[4] = {'R', 'G', 'X', '1'};
constexpr size_t kDescriptorBytes = 32;
// The first pose is the map's origin by definition: known exactly (1 um, 1 urad).
constexpr double kFirstPoseInformation = 1e12;

template <typename T>
void appendRaw(const T* data, size_t count, std::vector<uint8_t>* out) {
  const auto* bytes = reinterpret_cast<const uint8_t*>(data);
  out->insert(out->end(), bytes, bytes + count * sizeof(T));
}

// Nothing when the features are not as extractFeatures3d makes them (they stay in memory).
std::optional<std::vector<uint8_t>> encodeExtras(const KeyframeExtras& extras) {
  const Features3d& f = extras.features;
  const bool features_ok = f.uv.size() == f.size() && f.descriptors.rows == static_cast<int>(f.size()) &&
                           (f.size() == 0 || (f.descriptors.cols == static_cast<int>(kDescriptorBytes) &&
                                              f.descriptors.type() == CV_8UC1 && f.descriptors.isContinuous()));
  if (!features_ok) return std::nullopt;
  const uint32_t counts[2] = {static_cast<uint32_t>(extras.surface.size()), static_cast<uint32_t>(f.size())};
  std::vector<uint8_t> out;
  appendRaw(kExtrasMagic, 4, &out);
  appendRaw(counts, 2, &out);
  appendRaw(extras.surface.data(), extras.surface.size(), &out);
  if (counts[1] > 0) {
    appendRaw(f.p.data(), f.size(), &out);
    appendRaw(f.uv.data(), f.size(), &out);
    appendRaw(f.descriptors.data, f.size() * kDescriptorBytes, &out);
  }
  return out;
}

std::optional<KeyframeExtras> decodeExtras(const std::vector<uint8_t>& bytes) {
  uint32_t counts[2];
  if (bytes.size() < 12 || std::memcmp(bytes.data(), kExtrasMagic, 4) != 0) return std::nullopt;
  std::memcpy(counts, bytes.data() + 4, sizeof(counts));
  const size_t samples = counts[0], features = counts[1];
  const size_t expected = 12 + samples * sizeof(SurfaceSample) +
                          features * (sizeof(Eigen::Vector3f) + sizeof(Eigen::Vector2f) + kDescriptorBytes);
  if (bytes.size() != expected) return std::nullopt;
  KeyframeExtras extras;
  const uint8_t* at = bytes.data() + 12;
  const auto take = [&at](auto* dest, size_t count) {
    if (count == 0) return;  // an empty vector's data() may be null
    std::memcpy(static_cast<void*>(dest), at, count * sizeof(*dest));
    at += count * sizeof(*dest);
  };
  extras.surface.resize(samples);
  take(extras.surface.data(), samples);
  extras.features.p.resize(features);
  extras.features.uv.resize(features);
  take(extras.features.p.data(), features);
  take(extras.features.uv.data(), features);
  extras.features.descriptors.create(static_cast<int>(features), static_cast<int>(kDescriptorBytes), CV_8UC1);
  take(extras.features.descriptors.data, features * kDescriptorBytes);
  return extras;
}

// A fine-stage slot's search outcome, to restore an earlier attempt.
struct SlotOutcome {
  PointSlot* slot;
  bool searched, found;
  Eigen::Vector2d found_uv;
  int found_level;
};

double median(std::vector<double>* values) {
  if (values->empty()) return 0.0;
  const auto middle = values->begin() + static_cast<std::ptrdiff_t>(values->size() / 2);
  std::nth_element(values->begin(), middle, values->end());
  return *middle;
}

// A result worth a second attempt: with the other choice of coarse stage, or from another
// prediction (MotionOptions::retry_without_sbi).
bool poorResult(const TrackerOptions& options, double quality, double last_quality) {
  return quality < options.quality.good || quality < options.coarse.retry_quality_ratio * last_quality;
}

}  // namespace

bool coarseRetryWanted(const TrackerOptions& options, double quality, double last_quality, bool did_coarse) {
  return (did_coarse ? options.coarse.retry_without : options.coarse.retry_with) &&
         poorResult(options, quality, last_quality);
}

class Tracker::Impl {
 public:
  Impl(const PinholeCamera& camera, const TrackerOptions& options, SlamMode mode, int64_t map_id)
      : camera_(camera), options_(options), pose_options_(poseOptions(options, mode)),
        mode_(mode), map_id_(map_id), rng_(static_cast<uint32_t>(options.random_seed)),
        replica_(camera), motion_prior_(options.motion_prior) {
    // Nothing goes cold without a local map, so no store either.
    if (options.local_map.store_dir.empty() || options.local_map.keyframes <= 0) return;
    Expected<std::unique_ptr<KeyframeStore>> store = KeyframeStore::open(options.local_map.store_dir);
    if (!store) {
      store_status_ = Error{store.error() + " (tracker.local_map_store_dir; empty keeps cold keyframes in memory)"};
      return;
    }
    store_ = std::move(*store);
    replica_.setStore(store_.get(), options.local_map.store_points);
  }

  TrackResult track(const RgbdFrame& frame) {
    const auto start = std::chrono::steady_clock::now();
    TrackResult result = trackPose(frame);
    if (std::optional<KeyframeData> keyframe = finishFrame()) result.new_keyframe = std::move(keyframe);
    result.track_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return result;
  }

  TrackResult trackPose(const RgbdFrame& frame) {
    const auto start = std::chrono::steady_clock::now();
    std::optional<KeyframeData> late = finishFrame();  // the caller did not finish the last frame
    TrackResult result = trackFrame(frame);
    if (late) result.new_keyframe = std::move(late);  // trackFrame makes one only when it initialises
    publish(&result, frame.utime);
    result.keyframe_due = pending_keyframe_.has_value();
    stamp(&result, frame, start);
    return result;
  }

  TrackResult passLost(const RgbdFrame& frame) {
    if (!lost()) return trackPose(frame);
    const auto start = std::chrono::steady_clock::now();
    TrackResult result;
    if (std::optional<KeyframeData> late = finishFrame()) result.new_keyframe = std::move(late);
    result.pose.state = TrackingState::kLost;
    result.pose.T_w_c = T_c_w_.inverse();
    result.error = frameError(frame);  // a bad frame is reported as such, passed or not
    if (result.error.empty()) {
      ++lost_frames_;
      result.status = TrackResult::Status::kLost;
      result.lost_reason = "passed: a newer frame waits";
    }
    publish(&result, frame.utime);  // as trackPose() does, bad frames too
    stamp(&result, frame, start);
    return result;
  }

  void countPassedFrames(int frames) {
    if (lost() && frames > 0) lost_frames_ = static_cast<int>(std::min<int64_t>(INT_MAX, int64_t{lost_frames_} + frames));
  }

  bool followLost(const RgbdFrame& frame) {
    // A frame from before the last pose (of an earlier loss) would end this loss's dead
    // reckoning (time going back).
    if (!lost() || (last_pose_utime_ && frame.utime <= *last_pose_utime_) || frame.depth.cols != camera_.width ||
        frame.depth.rows != camera_.height || frame.depth.type() != CV_16UC1 || !(frame.depth_scale > 0.0)) {
      return false;
    }
    const long held = frames_reckoned_;
    stepDeadReckoning(frame);
    return frames_reckoned_ > held;
  }

  bool lost() const { return state_ == TrackingState::kLost && replica_.map().numKeyframes() > 0; }
  std::string frameError(const RgbdFrame& frame) const;  // why the tracker cannot use it; empty: usable

  // In the order track() always did them: the keyframe first, then the local map around
  // the frame's pose (with the new keyframe in it).
  std::optional<KeyframeData> finishFrame(bool real_time = false) {
    std::optional<KeyframeData> data;
    if (pending_keyframe_) {
      data = addKeyframe(std::move(*pending_keyframe_));
      pending_keyframe_.reset();
    }
    if (pending_local_map_) {
      updateLocalMap(*pending_local_map_, options_.local_map.changes_per_frame);
      pending_local_map_.reset();
    }
    if (rejoin_frame_) {
      tryRejoin(*rejoin_frame_, real_time);
      rejoin_frame_.reset();
    }
    return data;
  }
  long rejoins() const { return rejoins_; }
  long framesReckoned() const { return frames_reckoned_; }
  long rejoinTries() const { return rejoin_tries_; }

  bool applyMap(const MapUpdate& update, bool defer_cold) {
    countColdInView();  // before the replica changes
    reanchorBeforeCull(update.removed_keyframes);
    const bool known = replica_.apply(update, defer_cold);
    if (update.is_snapshot || !update.removed_keyframes.empty()) {  // keyframes the mapper culled
      for (auto it = extras_.begin(); it != extras_.end();) {
        it = replica_.map().hasKeyframe(it->first) ? std::next(it) : extras_.erase(it);
      }
      extras_cache_.clear();
      for (KeyframeId id : update.removed_keyframes) {
        if (id >= 0 && id <= INT_MAX) bow_index_.remove(static_cast<int>(id));
      }
    }
    // The loop closer joined the camera's part to another: that one's name is ours now.
    const KeyframeId part_before = part_;
    if (const Keyframe* first = replica_.map().keyframe(part_)) enterPart(first->part);
    // (Its first keyframe culled, and the part renamed: the newest keyframe's part is ours.)
    const auto& keyframes = replica_.map().keyframes();
    if (!keyframes.empty() && std::none_of(keyframes.begin(), keyframes.end(), [this](const auto& entry) {
          return entry.second->part == part_;
        })) {
      enterPart(keyframes.rbegin()->second->part);
    }
    followMapCorrection(/*joined=*/part_ != part_before);
    return known;
  }
  bool applyDeferredMap(size_t max_entries) {
    countColdInView();  // before the replica changes
    return replica_.applyDeferred(max_entries) > 0;
  }
  const Map& map() const { return replica_.map(); }
  const MapReplica& replica() const { return replica_; }
  const KeyframeStore* keyframeStore() const { return store_.get(); }
  const Status& keyframeStoreStatus() const { return store_status_; }
  void load(const LoadedMap& loaded, bool add_keyframes);

  void reset() {
    cold_count_.pending = false;  // the last projection's counts are for the map forgotten here
    points_in_view_.clear();
    views_.clear();
    replica_.clear();
    state_ = TrackingState::kInitialising;
    T_c_w_ = SE3();
    velocity_.setZero();
    motion_prior_.clear();
    lost_velocity_.setZero();
    lost_frames_ = 0;
    failed_relocalisations_ = 0;
    part_ = projection_part_ = 0;
    part_left_.reset();
    frames_since_rejoin_ = 0;
    rejoin_frame_.reset();
    rejoin_round_.reset();
    last_pose_utime_.reset();
    frames_since_keyframe_ = 0;
    uncertain_frames_ = 0;
    next_keyframe_id_ = 0;
    last_quality_ = 0.0;
    have_previous_sbi_ = false;
    extras_.clear();
    extras_cache_.clear();
    bow_index_ = BowIndex{};
    keyframes_allowed_ = true;
    anchor_.reset();
    offset_ = PublishedOffset{};
    last_utime_.reset();
    published_history_.clear();
    depth_reference_.reset();
    dead_reckoning_.reset();
    pending_keyframe_.reset();
    pending_local_map_.reset();
    depth_agreeing_found_ = 0;
  }

 private:
  TrackResult trackFrame(const RgbdFrame& frame);
  // The frame's time and sequence number, and the time spent on it since 'start'.
  static void stamp(TrackResult* result, const RgbdFrame& frame, std::chrono::steady_clock::time_point start) {
    result->track_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    result->pose.utime = frame.utime;
    result->pose.seq = frame.seq;
  }
  void prepareFrame(const RgbdFrame& frame);
  TrackResult initialise(const RgbdFrame& frame);
  bool addFirstKeyframe(const RgbdFrame& frame, KeyframeId id, const SE3& T_w_c, TrackResult* result);
  std::optional<TrackResult> startPart(const RgbdFrame& frame, std::string* why_not);
  // While in a part started where the camera was lost, finishFrame() relocalises frames
  // against the keyframes of the part it was lost in, one try a frame (RejoinRound): a camera
  // back in mapped space goes on in that part (its pose moved there, the published one taking
  // the difference in at correction_rate_*) instead of mapping it again.
  // real_time: a round's first try, which wants bags of words, is left to a later frame
  // while the vocabulary is still being trained (Tracker::finishFrame).
  void tryRejoin(const RgbdFrame& frame, bool real_time);
  // How far from where it was lost in the part it left the camera can be by 'frame' [m].
  double rejoinReachM(const RgbdFrame& frame) const;
  // The tracker is in 'part' now; back in the part it had left (or in the map's first part),
  // there is nothing to rejoin.
  void enterPart(KeyframeId part) {
    part_ = part;
    const bool first_part = !replica_.map().keyframes().empty() && replica_.map().keyframes().begin()->second->part == part;
    if (first_part || (part_left_ && part_left_->part == part)) leavePartLeft();
  }
  // Nothing to go back to: no rejoin, and no round of tries left over for a later loss.
  void leavePartLeft() {
    part_left_.reset();
    rejoin_round_.reset();
  }
  TrackResult relocalise(const RgbdFrame& frame);
  // Where a relocalisation tracks the frame from: a pose, the part whose points it projects,
  // whether the pose is near the camera's (the last pose, a features' pose: the fine stage
  // first) or a guess (a keyframe's view: the wide coarse search at once), and whether the
  // local map moves there first.
  struct RelocaliseStart {
    SE3 T_w_c;
    KeyframeId part = 0;
    bool near = false;
    bool thaw = true;
  };
  // 'extra_hot': keyframes the hot set may hold beyond the window while the local map is
  // there (updateLocalMap).
  Attempt relocaliseFrom(const RelocaliseStart& start, const RgbdFrame& frame, int extra_hot = 0);
  // 'extra_hot' keyframes beyond the window stay hot: a rejoin's try leaves the camera's own
  // window as it was (the next frames' local map updates freeze the surplus, oldest first).
  void updateLocalMap(const SE3& T_w_c, int max_thaws, int extra_hot = 0);
  void storeColdExtras();
  // Per keyframe id: points of which it is the source that the last projection put in the
  // image (found or not, hot or cold source). A cold keyframe's are counted when wanted
  // (countColdInView), from what the last projection left pending.
  std::vector<int> points_in_view_;
  struct ColdCount {
    SE3 T_c_w;
    KeyframeId part = 0;
    bool pending = false;
  } cold_count_;
  // The last projection's cold points in view, into points_in_view_, if not counted yet.
  // Called by their only reader (updateLocalMap) and before anything changes the replica, so
  // the counts are those the projection would have made.
  void countColdInView();
  TrackResult trackNormally(const RgbdFrame& frame);
  SE3 predictPose(bool use_sbi) const;
  // Coarse stage: kIfMoving when the start pose predicts image motion (coarseWanted),
  // kAlways when the motion is unknown (relocalisation), kNever for the fine-only retry.
  enum class Coarse { kIfMoving, kAlways, kNever };
  Attempt trackFrom(const SE3& T_c_w_start, const RgbdFrame& frame, Coarse coarse = Coarse::kIfMoving);
  // Tracks again from 'start' with 'coarse'; returns whichever of that and 'attempt'
  // explains more of its searched points, the slots left with the returned one's outcome.
  Attempt betterOf(const Attempt& attempt, const SE3& start, const RgbdFrame& frame, Coarse coarse);
  void saveOutcome(std::vector<SlotOutcome>* outcome) const;
  void restoreOutcome(const std::vector<SlotOutcome>& outcome);
  void projectAll(const SE3& T_c_w);
  // Leaves out of visible_ the points the frame's depth shows hidden behind a nearer surface
  // (OcclusionOptions; depth modes): they are neither searched nor counted in the quality.
  void dropHidden(const RgbdFrame& frame);
  bool drop_hidden_ = true;  // this frame's attempts leave hidden points out (trackFrame)
  int depth_agreeing_found_ = 0;  // the last accepted pose's found points agreeing with depth
  SE3 runStage(const std::vector<PointSlot*>& slots, const SE3& T_c_w, int radius_px,
               const RgbdFrame& frame, bool mark_inliers);
  void selectSubset(std::vector<PointSlot*>* slots, int max_count);
  bool isLost(const Attempt& attempt) const;
  bool coarseWanted(const SE3& T_c_w_start);
  bool poseFixed(const PoseUncertainty& uncertainty) const;
  // Whether keyframe 'id''s points from depth fix its pose T_c_w as tracking requires of a frame.
  bool constrainsPose(const std::vector<NewPoint>& points, KeyframeId id, const SE3& T_c_w) const;
  bool isReliable(const MapPoint& point) const {
    return point.times_projected < options_.quality.unreliable_after_searches ||
           point.times_found >= options_.quality.unreliable_found_ratio * point.times_projected;
  }
  // 'state' is reported; 'grade' (default: the same) is what the keyframe rule sees.
  TrackResult accept(const Attempt& attempt, const RgbdFrame& frame, TrackingState state,
                     std::optional<TrackingState> grade = std::nullopt);
  // Whether the pose is precise enough to be reported good (QualityOptions::good_step_*).
  bool preciseForFlight(const PoseUncertainty& uncertainty) const;
  // What the keyframe decision of a frame keeps until finishFrame() makes the keyframe:
  // the frame's grey image stays in grey_ until the next frame.
  struct PendingKeyframe {
    int64_t utime = 0;
    SE3 T_w_c;  // the map pose, not the published one
    std::vector<Measurement> measurements;
    cv::Mat depth;  // a copy: the caller's frame may be reused
    double depth_scale = 0.0;
    KeyframeId anchor = -1;  // the anchor keyframe and its pose then (KeyframeData::anchor)
    SE3 T_w_anchor = SE3();
  };
  KeyframeData addKeyframe(PendingKeyframe pending);
  std::vector<Measurement> foundMeasurements(const RgbdFrame& frame) const;
  double depthAt(const RgbdFrame& frame, const Eigen::Vector2d& uv) const;
  // The integrity checks of an attempt's pose: the image (photometric_integrity.h, every
  // mode) and the depth image (depth_integrity.h; not in mono, nor without a depth image).
  PoseIntegrity integrityOf(const Attempt& attempt, const RgbdFrame& frame);
  DepthIntegrity depthIntegrityOf(const Attempt& attempt, const RgbdFrame& frame);
  // An attempt the check refused is tracked again, fine stage only, from the prediction and
  // from the last good pose; the first that passes both checks is returned.
  std::optional<Attempt> retryConsistent(const SE3& predicted, const RgbdFrame& frame);
  TrackResult lostResult(const Attempt& attempt, std::string reason, bool inconsistent);
  // Depth-aided tracking (depth_alignment.h): whether the attempt's points are too weak,
  // and the joint fit of its found points and the nearest keyframes' surfaces. Returns the
  // attempt unchanged when depth does not hold the pose either.
  bool depthAidWanted(const Attempt& attempt, const RgbdFrame& frame) const;
  Attempt alignWithDepth(const Attempt& attempt, const RgbdFrame& frame);
  // Appends the surfaces of the part's keyframes nearest 'T_w_c' that have them, at most
  // DepthAlignmentOptions::keyframes of them.
  void appendKeyframeSurfaces(const SE3& T_w_c, std::vector<SurfaceAnchor>* anchors);
  // Lost: the dead reckoning follows the camera from the last pose (depth_dead_reckoning.h).
  void startDeadReckoning();
  void stepDeadReckoning(const RgbdFrame& frame);
  // Where the camera is taken to be while lost (T_c_w): where depth followed it, else where
  // the velocity at the loss carried it in 'coast_frames' frames.
  SE3 lostPoseGuess(int64_t utime, int coast_frames) const;
  void updateDepthReference(const Attempt& attempt, const RgbdFrame& frame);
  // What a keyframe leaves the tracker besides its pyramid (depth modes): surface samples
  // (depth-aided tracking) and 3-D features (relocalisation from anywhere), made on the
  // keyframe worker so that the frame which makes the keyframe does not wait for them.
  void rememberKeyframe(const Keyframe& keyframe);
  // Map corrections: after a map update, the tracker's pose moves as the keyframe nearest
  // it moved, and the published offset takes up the difference (TrackerOptions::correction_*).
  // joined: the camera's part was joined to another (mapper.h, "Parts"): the correction is
  // what the part's start was guessed wrong by, metres, beyond the fine stage's reach from
  // the old pose, so the tracker's own pose follows at once, whatever follow_map_corrections.
  void followMapCorrection(bool joined);
  void reanchorBeforeCull(const std::vector<KeyframeId>& removed);
  // The anchor: the source keyframe of most of the points found (the pose rests on them),
  // else the keyframe nearest the pose.
  void setAnchor();
  SE3 published(const SE3& T_w_c) const {
    return SE3(offset_.rotation * T_w_c.rotation(), T_w_c.translation() + offset_.position);
  }
  // Takes in the correction as far as the rates allow since the last frame, then sets the
  // result's published pose.
  void publish(TrackResult* result, int64_t utime);
  // A pose reported tracking whose published position leaves the constant-velocity
  // extrapolation of the last two by more than QualityOptions::good_step_m is reported
  // dodgy: a step the flight controller would feel as a jump, whatever the fit's sigma says
  // (corridor 900: poses 2.6-3.6 cm off with sigmas of 3 mm). A vehicle's own acceleration
  // moves it a * dt^2 from that extrapolation: 1.1 cm at 10 m/s^2 and 30 Hz.
  void holdStepAgainstMotion(TrackResult* result, int64_t utime);
  // A keyframe's extras, waiting for the worker if they are not made yet; null when the
  // keyframe has none.
  // In memory, or read back from the store: valid until the next call of extrasOf or
  // updateLocalMap (which moves extras to the store).
  const KeyframeExtras* extrasOf(KeyframeId id);
  bool anyExtras() const;
  // Relocalisation by features (feature_relocaliser.h) against 'candidates', best first, to
  // a pose within 'reach_m' of the last; '*features' holds the frame's ORB features once
  // extracted (here, if not yet).
  std::optional<Attempt> relocaliseByFeatures(const RgbdFrame& frame, const std::vector<KeyframeId>& candidates,
                                              double reach_m, std::optional<Features3d>* features,
                                              int extra_hot = 0);
  Features3d frameFeatures(const RgbdFrame& frame) const;
  // Whether a lost frame is compared with a shortlist only (TrackerOptions::relocalise_shortlist).
  bool shortlisted() const;
  // The shortlist: the keyframes nearest the last pose, then the best by bag of words, all
  // within 'reach_m' of the last pose; the feature relocaliser's candidates (the bag's best)
  // go to '*by_words'.
  std::vector<KeyframeId> relocalisationShortlist(const Features3d& features, double reach_m,
                                                  std::vector<KeyframeId>* by_words);
  // Adds the keyframes missing from the bag-of-words index (their extras read back if cold).
  void indexBags();
  void indexBag(KeyframeId id, const KeyframeExtras& extras);
  // Trains the project's vocabulary on a thread of its own (depth modes with reloc_features; once).
  void warmUpVocabulary();
  int cornerCount() const;  // FAST corners of this frame, all levels
  std::string lossReason(const Attempt& attempt) const;
  // The pose fit's options: depth residuals only where the mode tracks with depth.
  static PoseOptimizerOptions poseOptions(const TrackerOptions& options, SlamMode mode) {
    PoseOptimizerOptions pose = options.pose;
    pose.use_depth = pose.use_depth && depthInTracking(mode);
    return pose;
  }

  PinholeCamera camera_;
  TrackerOptions options_;
  PoseOptimizerOptions pose_options_;
  SlamMode mode_;
  int64_t map_id_;
  std::mt19937 rng_;

  // Cold keyframes' images and extras (keyframe_store.h; null: in memory), and why it is
  // null when the options asked for one. Before the replica, which uses it.
  std::unique_ptr<KeyframeStore> store_;
  Status store_status_;
  // The replica and the tracker's per-point search slots.
  MapReplica replica_;

  // Motion state.
  TrackingState state_ = TrackingState::kInitialising;
  SE3 T_c_w_;          // last good pose
  Vec6 velocity_ = Vec6::Zero();  // log of the last inter-frame motion (left, on T_c_w)
  // The constant-velocity prior of the pose fit (motion_prior.h), and the prior of the frame
  // being tracked (none while relocalising: a candidate's pose is not where the motion went).
  MotionPrior motion_prior_;
  std::optional<PosePrior> prior_;
  const PosePrior* priorOrNull() const { return prior_ ? &*prior_ : nullptr; }
  std::vector<PoseObservation> inlier_observations_;  // runStage's fit without the prior
  std::vector<size_t> inlier_index_;
  std::vector<uint8_t> inlier_kept_;
  bool coarse_possible_ = false;  // the last trackFrom had enough points for a coarse stage
  // While lost: the velocity when tracking was lost, and the frames lost since (a vehicle
  // does not stop when its tracker loses it: relocalise() tries where it coasted to).
  Vec6 lost_velocity_ = Vec6::Zero();
  int lost_frames_ = 0;
  int failed_relocalisations_ = 0;  // in a row, since the loss (new_part_after_failures)
  // The part of the map the camera is in (Keyframe::part; mapper.h, "Parts"): only its
  // points are tracked, since another part's lie where a guess put them. A relocalisation
  // tries each candidate keyframe's part (projection_part_).
  KeyframeId part_ = 0;
  KeyframeId projection_part_ = 0;
  // Where and when the camera was lost in the part it left for a new one: the bound on where
  // a return into that part may put it (tryRejoin).
  struct PartLeft {
    SE3 T_w_c;  // the last pose there, in that part's frame
    int64_t utime = 0;
    KeyframeId part = 0;
  };
  std::optional<PartLeft> part_left_;
  int frames_since_rejoin_ = 0;
  std::optional<RgbdFrame> rejoin_frame_;  // the frame finishFrame() tries (its depth a copy)
  // A rejoin's tries, spread over frames, each after that frame's pose is out, so that no
  // frame waits for a whole search (in one go, 17-37 ms on the 2-minute flight's world 1,
  // where a frame takes 2 ms): the round's first frame ranks the candidates and is tried by
  // features (a keyframe view tracked only where the features give a pose), the next frame
  // from the last pose in the part left, one frame each from the views of that part's
  // keyframes ranked on the first frame. A round starts rejoin_every_frames tracked frames
  // with depth after the last one ended.
  struct RejoinRound {
    std::vector<RelocalisationCandidate> views;  // [0]: the last pose in the part left (keyframe -1)
    size_t next = 0;
  };
  std::optional<RejoinRound> rejoin_round_;
  long rejoins_ = 0;
  long rejoin_tries_ = 0;  // one a frame at most (RejoinRound)
  // The time of the frame T_c_w_ was accepted on (none: a loaded map's start, where the
  // camera may be anywhere in it).
  std::optional<int64_t> last_pose_utime_;
  // How far from the last pose the camera can be by 'frame' (TrackerOptions::
  // relocalise_max_speed_m_s); infinite when unbounded.
  double relocaliseReachM(const RgbdFrame& frame) const;
  // How far the velocity at the loss has carried the camera from the last pose [m], counted
  // in frames as coasting counts them (or depth has, lostPoseGuess). No velocity known (lost right after a relocalisation,
  // which zeroes it): 0, the last pose is the best guess there is. Taking it as infinite
  // instead (good needed) refused right poses: the 2-minute flights' worlds 5 and 6 lost 94
  // and 303 frames in C3b whose poses had been 3.6 and 2.0 cm off on average (session 28).
  // Where depth followed the camera (depth_dead_reckoning.h), that is the travel.
  double lostTravelM(int64_t utime) const {
    const SE3 guess = lostPoseGuess(utime, lost_frames_);
    return (guess.inverse().translation() - T_c_w_.inverse().translation()).norm();
  }
  bool withinReach(const SE3& T_c_w, double reach_m) const {
    return (T_c_w.inverse().translation() - T_c_w_.inverse().translation()).norm() <= reach_m;
  }
  int frames_since_keyframe_ = 0;
  int uncertain_frames_ = 0;  // tracked frames in a row, since the last keyframe, with the
                              // pose sigma over keyframes.uncertain_pose_sigma_m
  KeyframeId next_keyframe_id_ = 0;
  bool keyframes_allowed_ = true;  // false: localise in a loaded map, add nothing to it
  double last_quality_ = 0.0;  // of the last accepted frame (0 after loss and reset)
  bool frame_inconsistent_ = false;  // this frame's first pose was refused by the check
  std::vector<Vec3> integrity_points_;  // scratch: the points the check projects...
  std::vector<PointSlot*> integrity_slots_;  // ...their slots
  std::vector<DepthVerdict> integrity_verdicts_;
  std::vector<uint8_t> reading_expected_;
  // A pose relocalised by features is tracked again from where it ended, this many times at
  // most, while the quality stays above this fraction of the previous pass's.
  static constexpr int kRelocaliseRefinePasses = 2;
  static constexpr double kRelocaliseRefineKeep = 0.9;
  std::unordered_map<KeyframeId, std::shared_future<KeyframeExtras>> extras_;  // hot, or not yet stored
  // Extras read back from the store, the newest last (a relocalisation's candidates, the
  // depth alignment's nearest keyframes): at most kExtrasCached.
  static constexpr size_t kExtrasCached = 16;
  std::deque<std::pair<KeyframeId, KeyframeExtras>> extras_cache_;
  // Every keyframe's bag of words, for the relocalisation shortlist (indexed when its extras
  // go cold, or at the first loss on a large map). The vocabulary is trained on a thread of
  // its own (~1.5 s, once per process) once the map has half the shortlist's keyframes, so
  // that the first loss does not wait for it, or at the first loss where a new part may
  // start (relocalise()): a map the mapper's culls kept under 14 keyframes until a new part's
  // first ones (15-16 at its first try to rejoin, the corridor) otherwise trained it in that
  // try, on the tracking thread (finishFrame): 3.1-4.5 s, the new part lost
  // (test_suite_new_part's setting, 3 of 24 runs). A use before the training is done waits
  // for it (rgbd-tracker's frame path does not: finishFrame's real_time); vocabulary_ready_
  // tells the keyframe worker.
  BowIndex bow_index_;
  std::future<void> vocabulary_warmup_;
  std::shared_ptr<std::atomic<bool>> vocabulary_ready_ = std::make_shared<std::atomic<bool>>(false);
  // The keyframe the pose rests on (setAnchor: the source of most points found, else the
  // nearest), and its pose then: map corrections are measured on it, and keyframes and
  // results name it (KeyframeData::anchor, TrackResult::anchor).
  struct Anchor {
    KeyframeId id;
    SE3 T_w_k;
  };
  std::optional<Anchor> anchor_;
  // Published pose = map pose turned by 'rotation' about the camera centre, then shifted by
  // 'position' (world frame): the correction not yet taken in.
  struct PublishedOffset {
    Vec3 position = Vec3::Zero();
    Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  };
  PublishedOffset offset_;
  std::optional<int64_t> last_utime_;  // of the last frame tracked [us]
  // The last two published positions and their times, newest first (reset when a frame has
  // no pose): the motion a reported step is held against (QualityOptions::good_step_m).
  std::vector<std::pair<int64_t, Vec3>> published_history_;
  std::vector<SurfaceAnchor> anchors_;  // scratch: one frame's samples in the world
  // Lost: the camera followed by depth from the last pose (TrackerOptions::
  // relocalise_dead_reckoning); none in mono, with depth_align off, or before the first loss.
  std::optional<DepthDeadReckoning> dead_reckoning_;
  std::vector<SurfaceAnchor> reckoning_anchors_;  // scratch: the keyframes' surfaces near it
  long frames_reckoned_ = 0;  // lost frames depth held, over the run

  // The last frame's work that its pose did not need, not yet done (finishFrame): its
  // keyframe, and the local map around its pose (freezing keyframes that left it, thawing
  // those that came into it: JPEG coding, the store, pyramids).
  std::optional<PendingKeyframe> pending_keyframe_;
  std::optional<SE3> pending_local_map_;  // the map pose the local map is centred on

  // Per-frame buffers, reused.
  cv::Mat grey_;
  ImagePyramid pyramid_;
  std::vector<LevelCorners> corners_;
  SmallBlurryImage sbi_, previous_sbi_;
  bool have_previous_sbi_ = false;
  std::vector<KeyframeView> views_;
  std::vector<PointSlot*> visible_, stage_;
  std::vector<PoseObservation> observations_;
  std::vector<uint8_t> inliers_;
  std::vector<double> depths_, displacements_;
  std::vector<SlotOutcome> outcome_;
  // Depth-aided tracking's own reference (DepthAlignmentOptions::reference_step_m): the
  // surfaces of a recent depth-aided frame, made on the worker, and that frame's pose; none
  // while the points alone hold the pose.
  struct DepthReference {
    std::shared_future<std::vector<SurfaceSample>> samples;
    SE3 T_w_c;
  };
  std::optional<DepthReference> depth_reference_;
  // Makes the keyframes' extras; last, so that it is joined before anything else goes.
  BackgroundWorker keyframe_worker_;
  // J^T W J of the last fine stage's pose fit (zero when it failed).
  Eigen::Matrix<double, 6, 6> fine_information_ = Eigen::Matrix<double, 6, 6>::Zero();
};

// ---------------------------------------------------------------------------------------
// Frame flow

std::string Tracker::Impl::frameError(const RgbdFrame& frame) const {
  if (frame.colour.empty()) return "frame has no colour image";
  if (frame.colour.cols != camera_.width || frame.colour.rows != camera_.height ||
      (frame.colour.type() != CV_8UC3 && frame.colour.type() != CV_8UC1)) {
    return "frame is " + std::to_string(frame.colour.cols) + "x" + std::to_string(frame.colour.rows) +
           ", camera '" + camera_.name + "' is " + std::to_string(camera_.width) + "x" +
           std::to_string(camera_.height) + " (8-bit colour or grey expected)";
  }
  return "";
}

TrackResult Tracker::Impl::trackFrame(const RgbdFrame& frame) {
  TrackResult result;
  result.pose.state = state_;
  result.pose.T_w_c = T_c_w_.inverse();
  result.error = frameError(frame);
  if (!result.error.empty()) return result;
  prepareFrame(frame);
  frame_inconsistent_ = false;
  TrackResult tracked;
  // Hidden points are left out only where the depth image vouched for the last pose (its
  // found points agreeing with their readings, OcclusionOptions::min_agreeing; not after a
  // relocalisation, accept()), and only in a frame tracked normally: from the prediction,
  // at the coarse stage's pose and in the retries from the last pose. A pose that puts the
  // camera behind where it is makes every point ahead look hidden behind the surface it
  // lies on, and, left out, those points would no longer count against that pose. (A
  // safeguard by reasoning: after the wrong relocalisation of test_rgbd_slam_flight.sh's
  // pinned settings, 1 m back, the frames that followed had 0-8 such points, and the run
  // was the same without it. Open: the coarse stage's pose is not vouched for; the hidden
  // set could be decided once at the start pose, docs/open_work.md, session 27.)
  drop_hidden_ = state_ != TrackingState::kLost && depth_agreeing_found_ >= options_.occlusion.min_agreeing;
  projection_part_ = part_;
  if (replica_.map().numKeyframes() == 0) tracked = initialise(frame);
  else if (state_ == TrackingState::kLost) tracked = relocalise(frame);
  else {
    prior_ = motion_prior_.predict(frame.utime);
    tracked = trackNormally(frame);
    prior_.reset();
  }
  std::swap(previous_sbi_, sbi_);
  have_previous_sbi_ = true;
  tracked.inconsistent = frame_inconsistent_;
  if (tracked.status == TrackResult::Status::kTracked || tracked.status == TrackResult::Status::kRelocalised) {
    pending_local_map_ = tracked.pose.T_w_c;  // finishFrame
    if (part_left_ && !tracked.new_part && options_.rejoin_every_frames > 0 && !frame.depth.empty() &&
        (rejoin_round_ || ++frames_since_rejoin_ >= options_.rejoin_every_frames)) {
      frames_since_rejoin_ = 0;
      rejoin_frame_ = RgbdFrame{};
      rejoin_frame_->depth = frame.depth.clone();
      rejoin_frame_->depth_scale = frame.depth_scale;
      rejoin_frame_->utime = frame.utime;
      rejoin_frame_->seq = frame.seq;
    }
  }
  return tracked;
}

// The keyframes nearest 'T_w_c' hot, the rest cold (LocalMapOptions), at most 'max_thaws'
// thawed now: the others of the window follow in the next frames.
// Wanted first: the sources of the most points in view at the last projection, hot or cold
// (so points the camera sees are not lost to the window), then the nearest keyframes.
void Tracker::Impl::updateLocalMap(const SE3& T_w_c, int max_thaws, int extra_hot) {
  const LocalMapOptions& o = options_.local_map;
  if (o.keyframes <= 0 || replica_.map().numKeyframes() <= static_cast<size_t>(o.keyframes)) return;
  countColdInView();
  std::vector<std::pair<int, KeyframeId>> in_view;
  for (size_t id = 0; id < points_in_view_.size(); ++id) {
    if (points_in_view_[id] > 0) in_view.emplace_back(-points_in_view_[id], static_cast<KeyframeId>(id));
  }
  std::sort(in_view.begin(), in_view.end());
  std::vector<KeyframeId> wanted;
  for (const auto& [minus_points, id] : in_view) wanted.push_back(id);
  for (KeyframeId id : replica_.map().nearestKeyframesInPart(T_w_c, static_cast<size_t>(o.keyframes), projection_part_)) {
    if (static_cast<size_t>(id) >= points_in_view_.size() || points_in_view_[id] == 0) wanted.push_back(id);
  }
  // At most the window: the sources of the points in view and the nearest keyframes together
  // once made 76 hot keyframes of a window of 40 on the 2-minute flight (+20 MB of heap that
  // malloc then kept). The list's tail is left out: the farthest of the nearest keyframes,
  // then the sources of the fewest points in view.
  if (wanted.size() > static_cast<size_t>(o.keyframes)) wanted.resize(static_cast<size_t>(o.keyframes));
  replica_.updateLocalMap(wanted, max_thaws, o.changes_per_frame, o.jpeg_quality, o.keyframes + extra_hot);
  storeColdExtras();
}

// Extras of cold keyframes, once made, go to the store (they are read back when wanted).
void Tracker::Impl::storeColdExtras() {
  if (!store_) return;
  for (auto it = extras_.begin(); it != extras_.end();) {
    const Keyframe* keyframe = replica_.map().keyframe(it->first);
    if (!keyframe || !keyframe->cold() ||
        it->second.wait_for(std::chrono::seconds(0)) != std::future_status::ready) {
      ++it;
      continue;
    }
    // The bag only if made already (the vocabulary ready): else at the first loss that needs it.
    if (it->second.get().bag) indexBag(it->first, it->second.get());
    const std::optional<std::vector<uint8_t>> bytes = encodeExtras(it->second.get());
    if (!bytes) {
      ++it;
      continue;
    }
    if (!store_->put(it->first, KeyframeStore::Kind::kExtras, *bytes)) return;  // full: they stay here
    it = extras_.erase(it);
  }
}

void Tracker::Impl::prepareFrame(const RgbdFrame& frame) {
  if (frame.colour.channels() == 1) frame.colour.copyTo(grey_);
  else cv::cvtColor(frame.colour, grey_, cv::COLOR_BGR2GRAY);
  buildPyramid(grey_, kMaxLevels, &pyramid_);
  detectPyramidCorners(pyramid_, options_.keyframe_build.corners, /*with_maxima=*/false, &corners_);
  makeSmallBlurryImage(pyramid_, &sbi_);
}

TrackResult Tracker::Impl::initialise(const RgbdFrame& frame) {
  TrackResult result;
  result.pose.state = TrackingState::kInitialising;
  if (!addFirstKeyframe(frame, 0, SE3(), &result)) {
    result.status = TrackResult::Status::kNotInitialised;
    return result;
  }
  result.status = TrackStatus::kInitialised;
  return result;
}

// A map's first keyframe (keyframe 0 at the world's origin) or a new part's (startPart):
// made from the frame's points from depth alone, which must be enough and fix the pose as
// well as tracking requires of a frame; the tracker then tracks from it. False, with
// result->error saying why, when the frame cannot start one.
bool Tracker::Impl::addFirstKeyframe(const RgbdFrame& frame, KeyframeId id, const SE3& T_w_c, TrackResult* result) {
  if (frame.depth.empty() || frame.depth.size() != frame.colour.size()) {
    result->error = "no depth to initialise";
    return false;
  }
  KeyframeData data;
  data.utime = frame.utime;
  data.map_id = map_id_;
  data.id = id;
  data.T_w_c = T_w_c;
  data.grey = grey_.clone();
  data.depth = frame.depth.clone();
  data.depth_scale = frame.depth_scale;
  data.new_part = id != 0;
  std::unique_ptr<Keyframe> keyframe = makeKeyframe(data, options_.keyframe_build);
  keyframe->part = id;  // keyframe 0's is 0
  const std::vector<NewPoint> points =
      createPointsFromDepth(*keyframe, camera_, options_.depth_points, provisionalPointId(id, 0));
  if (static_cast<int>(points.size()) < options_.init_min_points) {
    result->error = "no depth to initialise (" + std::to_string(points.size()) + " points, " +
                    std::to_string(options_.init_min_points) + " needed)";
    return false;
  }
  if (!constrainsPose(points, id, T_w_c.inverse())) {
    result->error = "no depth to initialise (" + std::to_string(points.size()) + " points do not fix the pose)";
    return false;
  }
  rememberKeyframe(*keyframe);
  keyframe->releaseMappingData();
  countColdInView();  // before the replica changes
  replica_.addKeyframe(std::move(keyframe));
  for (const NewPoint& np : points) {
    if (!isProvisionalPointOf(np.point.id, id)) break;
    replica_.addProvisionalPoint(np);
    data.measurements.push_back(np.measurement);
    data.new_points.push_back(np.point.data());
  }
  next_keyframe_id_ = id + 1;
  part_ = projection_part_ = id;
  frames_since_keyframe_ = 0;
  uncertain_frames_ = 0;
  T_c_w_ = T_w_c.inverse();
  last_pose_utime_ = frame.utime;
  velocity_.setZero();
  motion_prior_.reset(frame.utime, T_c_w_, kFirstPoseInformation * Mat6::Identity());
  state_ = TrackingState::kTracking;
  result->pose.state = TrackingState::kTracking;
  result->pose.T_w_c = T_w_c;
  result->pose.points_tracked = static_cast<int>(data.new_points.size());
  result->pose.quality = 1.0;
  result->new_keyframe = std::move(data);
  return true;
}

// Lost where the map has nothing to relocalise against (TrackerOptions::new_part_after_failures
// relocalisations failed in a row): a new part of the map from this frame, as from a first
// frame, at the pose the velocity at the loss carried the camera to. The pose is published
// as dodgy: its place relative to the map before is that guess until the ground's loop
// closer joins the part to the rest (mapper.h, "Parts").
std::optional<TrackResult> Tracker::Impl::startPart(const RgbdFrame& frame, std::string* why_not) {
  const SE3 coasted = lostPoseGuess(frame.utime, std::min(lost_frames_, options_.relocalise_coast_frames));
  const PartLeft left{T_c_w_.inverse(), last_pose_utime_.value_or(frame.utime), part_};
  TrackResult result;
  if (!addFirstKeyframe(frame, next_keyframe_id_, coasted.inverse(), &result)) {
    *why_not = "no new part: " + result.error;
    return std::nullopt;
  }
  result.status = TrackStatus::kTracked;
  result.pose.state = TrackingState::kDodgy;
  result.new_part = true;
  result.part_start_reckoned = dead_reckoning_ && dead_reckoning_->framesHeld() > 0;
  if (!part_left_) part_left_ = left;  // a part started from a new part: bounded from the first loss
  rejoin_round_.reset();  // a round's views were ranked before this loss
  frames_since_rejoin_ = 0;
  lost_frames_ = 0;
  failed_relocalisations_ = 0;
  lost_velocity_.setZero();
  last_quality_ = 1.0;
  anchor_.reset();
  return result;
}

void Tracker::Impl::tryRejoin(const RgbdFrame& frame, bool real_time) {
  if (!part_left_ || !options_.reloc_features.enabled) return;
  const Map& map = replica_.map();
  // Only into the part the camera was lost in: where it was lost is known in that part's
  // frame alone, and it bounds where the return may put the camera.
  const KeyframeId into = part_left_->part;
  // That part joined another on the ground (its first keyframe renamed) or gone: where the
  // camera was lost is no longer known in any part's frame.
  const Keyframe* first = map.keyframe(into);
  if (!first || first->part != into) return leavePartLeft();
  if (into == part_) return;
  // The camera's own window stays hot through a try (nothing to thaw back after it).
  const int extra_hot = options_.local_map.relocalise_thaws;
  const SE3 T_c_w_before = T_c_w_;
  std::optional<Attempt> attempt;
  if (!rejoin_round_) {
    if (real_time && !vocabulary_ready_->load()) {
      warmUpVocabulary();
      if (vocabulary_warmup_.valid()) return;  // training: the try after the next rejoin_every_frames
    }
    ++rejoin_tries_;
    // Only keyframes of that part that may see where the camera can be: within the reach
    // plus the depth range of where it was lost (as relocalise() bounds its candidates), and
    // on a large part the shortlist of a relocalisation: the nearest to where it was lost,
    // then the bag of words' best (the vocabulary waited for once: determinism).
    const double keyframe_reach_m = rejoinReachM(frame) + options_.keyframe_build.max_depth_m;
    std::optional<Features3d> features = frameFeatures(frame);
    std::vector<KeyframeId> among, by_words;
    for (const auto& [id, keyframe] : map.keyframes()) {
      if (keyframe->part == into &&
          (keyframe->T_w_c.translation() - part_left_->T_w_c.translation()).norm() <= keyframe_reach_m) {
        among.push_back(id);
      }
    }
    BowVector bag;
    if (features->size() > 0) {
      indexBags();
      bag = projectVocabulary().bag(features->descriptors);
    }
    const std::vector<KeyframeId> shortlist =
        rgbdslam::relocalisationShortlist(map, bow_index_, bag, part_left_->T_w_c, keyframe_reach_m,
                                          static_cast<size_t>(options_.relocalise_shortlist),
                                          static_cast<size_t>(options_.reloc_features.candidates), &by_words, into);
    if (among.size() > static_cast<size_t>(options_.relocalise_shortlist)) among = shortlist;
    // First where the camera was lost (it often comes back the way it went), then the views
    // of the keyframes whose small blurry images are most like this frame's (previous_sbi_
    // after trackFrame).
    rejoin_round_ = RejoinRound{{RelocalisationCandidate{-1, 0.0, part_left_->T_w_c}}, 0};
    for (const RelocalisationCandidate& view :
         relocalisationCandidates(map, previous_sbi_, camera_, options_.relocalise_candidates, &among)) {
      rejoin_round_->views.push_back(view);
    }
    attempt = relocaliseByFeatures(frame, by_words, std::numeric_limits<double>::infinity(), &features, extra_hot);
  } else {
    // The next view whose keyframe is still in the map (culled since the round's first frame).
    RelocalisationCandidate view = rejoin_round_->views[rejoin_round_->next++];
    while (view.keyframe >= 0 && !map.keyframe(view.keyframe) && rejoin_round_->next < rejoin_round_->views.size()) {
      view = rejoin_round_->views[rejoin_round_->next++];
    }
    if (rejoin_round_->next >= rejoin_round_->views.size()) rejoin_round_.reset();
    const bool last_pose = view.keyframe < 0;
    if (!last_pose && !map.keyframe(view.keyframe)) return;
    ++rejoin_tries_;
    const Attempt tried = relocaliseFrom(RelocaliseStart{view.T_w_c, into, last_pose, true}, frame, extra_hot);
    if (!isLost(tried) && tried.quality >= options_.quality.good && integrityOf(tried, frame).consistent()) attempt = tried;
  }
  const KeyframeId found_part = projection_part_;
  projection_part_ = part_;
  if (!attempt || found_part != into) return;
  if ((attempt->T_c_w.inverse().translation() - part_left_->T_w_c.translation()).norm() > rejoinReachM(frame)) return;
  // The camera's pose moves into the found part; the published one takes the move in as it
  // takes a map correction (followMapCorrection).
  const SE3 old_pose = T_c_w_before.inverse(), new_pose = attempt->T_c_w.inverse();
  const SE3 correction = new_pose * old_pose.inverse();
  const SE3 old_published = published(old_pose);
  T_c_w_ = attempt->T_c_w;
  motion_prior_.moveWorld(correction);
  if (depth_reference_) depth_reference_->T_w_c = correction * depth_reference_->T_w_c;
  if (dead_reckoning_) dead_reckoning_->moveWorld(correction);
  offset_.position = old_published.translation() - new_pose.translation();
  offset_.rotation = (old_published.rotation() * new_pose.rotation().inverse()).normalized();
  enterPart(found_part);
  projection_part_ = part_;
  rejoin_round_.reset();
  setAnchor();
  ++rejoins_;
}

// Within the reach of the vehicle's speed from where it was lost (relocaliseReachM's bound).
double Tracker::Impl::rejoinReachM(const RgbdFrame& frame) const {
  if (options_.relocalise_max_speed_m_s <= 0.0) return std::numeric_limits<double>::infinity();
  const double away_s = std::max(0.0, static_cast<double>(frame.utime - part_left_->utime) * 1e-6);
  return options_.relocalise_max_speed_m_s * away_s + 1.0;
}

// The replica as the file holds it, every keyframe acknowledged (the mapper loads the same
// file). Lost from the start: the relocaliser tries the last pose first, taken to be where
// the saved session started (keyframe 0, where a vehicle back on its pad is), then the
// keyframes whose small blurry images are most like the frame's.
void Tracker::Impl::load(const LoadedMap& loaded, bool add_keyframes) {
  reset();
  // A large map starts lost on its shortlist: the vocabulary from the start.
  if (2 * loaded.keyframes.size() >= static_cast<size_t>(options_.relocalise_shortlist)) warmUpVocabulary();
  for (size_t i = 0; i < loaded.keyframes.size(); ++i) {
    std::unique_ptr<Keyframe> keyframe = loaded.buildKeyframe(i, options_.keyframe_build);
    rememberKeyframe(*keyframe);
    keyframe->releaseMappingData();
    replica_.addAcknowledgedKeyframe(std::move(keyframe));
  }
  for (const MapPointData& p : loaded.points) replica_.addAcknowledgedPoint(MapPoint(p));
  next_keyframe_id_ = loaded.nextKeyframeId();
  keyframes_allowed_ = add_keyframes;
  if (loaded.keyframes.empty()) return;  // nothing to localise in: initialise as usual
  T_c_w_ = loaded.keyframes.front().T_w_c.inverse();
  motion_prior_.clear();
  state_ = TrackingState::kLost;
}

SE3 Tracker::Impl::predictPose(bool use_sbi) const {
  Vec6 xi = options_.motion.velocity_damping * velocity_;
  if (use_sbi && have_previous_sbi_) {
    // PTAM: the SBI rotation replaces the rotational velocity, and sideways translation
    // (which the SBI alignment has already explained as rotation) is dropped.
    const SE3 T_old_new =
        rotationFromSe2(alignSmallBlurryImages(previous_sbi_, sbi_), camera_, sbi_.scale);
    xi.tail<3>() = T_old_new.inverse().log().tail<3>();
    xi(0) = 0.0;
    xi(1) = 0.0;
  }
  return SE3::exp(xi) * T_c_w_;
}

TrackResult Tracker::Impl::trackNormally(const RgbdFrame& frame) {
  const bool use_sbi = options_.motion.use_sbi_rotation && have_previous_sbi_;
  const SE3 predicted = predictPose(use_sbi);
  Attempt attempt = trackFrom(predicted, frame);
  // The coarse stage fits a few dozen matches at the coarsest levels, where fine texture
  // gives many wrong ones; now and then they pull the pose off, and the fine stage, which
  // searches near that pose, cannot bring it back. A poor result after a coarse stage is
  // therefore compared with the fine stage alone from the prediction, and the attempt that
  // explains more of its searched points is kept. So is one whose quality dropped sharply
  // from the last frame's (CoarseStageOptions::retry_quality_ratio).
  // (Without enough points at the coarse levels the retry with it would be the same fine stage.)
  if ((attempt.did_coarse || coarse_possible_) &&
      coarseRetryWanted(options_, attempt.quality, last_quality_, attempt.did_coarse)) {
    attempt = betterOf(attempt, predicted, frame, attempt.did_coarse ? Coarse::kNever : Coarse::kAlways);
  }
  if (use_sbi && options_.motion.retry_without_sbi && poorResult(options_, attempt.quality, last_quality_)) {
    attempt = betterOf(attempt, predictPose(false), frame, Coarse::kIfMoving);
  }
  if (depthAidWanted(attempt, frame)) attempt = alignWithDepth(attempt, frame);
  if (isLost(attempt)) return lostResult(attempt, lossReason(attempt), false);
  if (const PoseIntegrity integrity = integrityOf(attempt, frame); !integrity.consistent()) {
    frame_inconsistent_ = true;
    std::optional<Attempt> retried = retryConsistent(predicted, frame);
    if (!retried) return lostResult(attempt, integrity.describe(), true);
    attempt = *retried;
  }
  // PTAM's grade (found / searched) decides keyframes; the report also asks for precision.
  const TrackingState grade = attempt.quality >= options_.quality.good && !attempt.depth_aided
                                  ? TrackingState::kTracking
                                  : TrackingState::kDodgy;
  const bool precise = preciseForFlight(attempt.uncertainty);
  return accept(attempt, frame, grade == TrackingState::kTracking && !precise ? TrackingState::kDodgy : grade,
                grade);
}

// From a keyframe's view the camera may be anywhere near: the wide coarse search first.
// From a near pose the camera has often hardly moved, and on weak texture the coarse stage
// can pull a pose off (the corridor), so the fine stage alone comes first; short of a good
// result the coarse stage is tried as well (the camera moved a few pixels: 0.14 of the
// points found without it, 0.97 with it, two frames after a loss in the room), and the
// attempt that explains more of its searched points is kept.
Attempt Tracker::Impl::relocaliseFrom(const RelocaliseStart& start, const RgbdFrame& frame, int extra_hot) {
  projection_part_ = start.part;
  if (start.thaw) updateLocalMap(start.T_w_c, options_.local_map.relocalise_thaws, extra_hot);
  const SE3 T_c_w = start.T_w_c.inverse();
  Attempt attempt = trackFrom(T_c_w, frame, start.near ? Coarse::kNever : Coarse::kAlways);
  if (start.near && (isLost(attempt) || attempt.quality < options_.quality.good)) {
    attempt = betterOf(attempt, T_c_w, frame, Coarse::kAlways);
  }
  return attempt;
}

TrackResult Tracker::Impl::relocalise(const RgbdFrame& frame) {
  // Lost where a new part may start: its tries to rejoin the part it left want bags of
  // words, whatever the map's size (a large map's shortlist has them already). Trained off
  // this thread, while the relocalisation goes on without them on a small map.
  if (options_.new_part_after_failures > 0 && keyframes_allowed_) warmUpVocabulary();
  const int wanted = std::max(options_.relocalise_candidates, options_.reloc_features.candidates);
  std::optional<Features3d> features;       // the frame's ORB features, extracted at most once
  std::vector<KeyframeId> feature_candidates;
  std::vector<RelocalisationCandidate> ranked;
  const double reach_m = relocaliseReachM(frame);
  // A keyframe may see where the camera is from up to the depth range away.
  const double keyframe_reach_m = reach_m + options_.keyframe_build.max_depth_m;
  if (shortlisted()) {
    features = frameFeatures(frame);
    const std::vector<KeyframeId> shortlist = relocalisationShortlist(*features, keyframe_reach_m, &feature_candidates);
    ranked = relocalisationCandidates(replica_.map(), sbi_, camera_, wanted, &shortlist);
  } else {
    std::vector<KeyframeId> within;
    if (std::isfinite(keyframe_reach_m)) within = replica_.map().keyframesWithin(T_c_w_.inverse(), keyframe_reach_m);
    ranked = relocalisationCandidates(replica_.map(), sbi_, camera_, wanted,
                                      std::isfinite(keyframe_reach_m) ? &within : nullptr);
    for (const RelocalisationCandidate& candidate : ranked) feature_candidates.push_back(candidate.keyframe);
  }
  std::vector<RelocalisationCandidate> candidates(
      ranked.begin(), ranked.begin() + std::min<std::ptrdiff_t>(static_cast<std::ptrdiff_t>(ranked.size()),
                                                               options_.relocalise_candidates));
  // The last good pose first: after a short disturbance the camera is often still near it.
  // Then where depth followed the camera to (depth_dead_reckoning.h), or else, for
  // TrackerOptions::relocalise_coast_frames, where the velocity at the loss carried it since
  // (tried as a pose near the last one: fine stage first, dodgy is enough).
  ++lost_frames_;
  stepDeadReckoning(frame);
  // (A guess depth held long ago is tried only within the coast's frames, as the coast is;
  // relocalise_coast_frames 0 means the last pose only, whatever depth says.)
  const bool reckoned = options_.relocalise_coast_frames > 0 && dead_reckoning_ &&
                        dead_reckoning_->heldRecently(frame.utime);
  if (reckoned || (!lost_velocity_.isZero() && lost_frames_ <= options_.relocalise_coast_frames)) {
    candidates.insert(candidates.begin(),
                      RelocalisationCandidate{-1, 0.0, lostPoseGuess(frame.utime, lost_frames_).inverse()});
  }
  candidates.insert(candidates.begin(), RelocalisationCandidate{-1, 0.0, T_c_w_.inverse()});
  const double last_pose_reach_m = options_.relocalise_last_pose_reach_m;
  const bool last_pose_in_reach = last_pose_reach_m > 0.0 && lostTravelM(frame.utime) <= last_pose_reach_m;
  for (size_t i = 0; i < candidates.size(); ++i) {
    const RelocalisationCandidate& candidate = candidates[i];
    const bool near_last = candidate.keyframe < 0;
    const bool dodgy_enough = near_last && (i > 0 || last_pose_in_reach);  // [0]: the last pose
    const KeyframeId part = near_last ? part_ : replica_.map().keyframe(candidate.keyframe)->part;
    const Attempt attempt = relocaliseFrom(RelocaliseStart{candidate.T_w_c, part, near_last, !near_last}, frame);
    // A keyframe's view is a guess from the small blurry image: only a good result proves
    // it. From the last pose the bar is normal tracking's (dodgy is enough, the pose must be
    // fixed): where many points are hidden or unmatchable for a stretch (the corridor's
    // glass cabinets close by) the quality stays below good although the pose is right,
    // and a tracker that lost such a stretch once would otherwise never come back. But not
    // once the camera has coasted out of the last pose's reach (relocalise_last_pose_reach_m).
    if (isLost(attempt) || (!dodgy_enough && attempt.quality < options_.quality.good)) continue;
    if (!withinReach(attempt.T_c_w, reach_m)) continue;       // a lookalike place
    if (!integrityOf(attempt, frame).consistent()) continue;  // a wrong pose is worse than none
    velocity_.setZero();
    enterPart(projection_part_);
    return accept(attempt, frame, TrackingState::kRelocalised);
  }
  if (std::optional<Attempt> attempt = relocaliseByFeatures(frame, feature_candidates, reach_m, &features)) {
    velocity_.setZero();
    enterPart(projection_part_);
    return accept(*attempt, frame, TrackingState::kRelocalised);
  }
  projection_part_ = part_;
  // Only a frame that could have been found counts: one with depth and corners (a covered
  // camera's black frames are no attempt).
  if (!frame.depth.empty() && cornerCount() >= options_.init_min_points) ++failed_relocalisations_;
  const int after = options_.new_part_after_failures;
  std::string why_not;
  if (after > 0 && failed_relocalisations_ >= after && keyframes_allowed_ && mode_ != SlamMode::kMono) {
    if (std::optional<TrackResult> started = startPart(frame, &why_not)) return *started;
  }
  TrackResult result;
  result.lost_reason = why_not;
  result.status = TrackStatus::kLost;
  result.pose.state = TrackingState::kLost;
  result.pose.T_w_c = T_c_w_.inverse();
  return result;
}

PoseIntegrity Tracker::Impl::integrityOf(const Attempt& attempt, const RgbdFrame& frame) {
  PoseIntegrity integrity;
  integrity.image = checkPhotometricIntegrity(stage_, attempt.T_c_w, pyramid_, camera_, options_.search,
                                              options_.photometric);
  integrity.depth = depthIntegrityOf(attempt, frame);
  return integrity;
}

DepthIntegrity Tracker::Impl::depthIntegrityOf(const Attempt& attempt, const RgbdFrame& frame) {
  for (PointSlot* slot : stage_) slot->depth_verdict = DepthVerdict::kUnchecked;  // none left from another attempt
  if (!options_.integrity.enabled || !depthInTracking(mode_) || frame.depth.empty()) return DepthIntegrity{};
  // Points seen through at most of their accepted poses (glass, wrong points) say nothing.
  integrity_points_.clear();
  integrity_slots_.clear();
  reading_expected_.clear();
  for (PointSlot* slot : stage_) {
    if (slot->point->depth_record.mostlySeenThrough()) continue;
    integrity_points_.push_back(slot->point->p_w);
    integrity_slots_.push_back(slot);
    // Found where the pose puts it (so not hidden by something nearer than the sensor's
    // range, which gives no reading either), and its record expects a reading there.
    reading_expected_.push_back(slot->found && slot->point->depth_record.expectsReadingAt((attempt.T_c_w * slot->point->p_w).z()));
  }
  const DepthIntegrity integrity =
      checkDepthIntegrity(integrity_points_, attempt.T_c_w, frame, camera_, options_.pose.noise,
                          options_.keyframe_build.min_depth_m, options_.keyframe_build.max_depth_m,
                          options_.integrity, &integrity_verdicts_, &reading_expected_);
  for (size_t i = 0; i < integrity_slots_.size(); ++i) {
    integrity_slots_[i]->depth_verdict = integrity_verdicts_[i];
  }
  return integrity;
}

std::optional<Attempt> Tracker::Impl::retryConsistent(const SE3& predicted, const RgbdFrame& frame) {
  for (const SE3& start : {predicted, T_c_w_}) {
    const Attempt retry = trackFrom(start, frame, Coarse::kNever);
    if (!isLost(retry) && integrityOf(retry, frame).consistent()) return retry;
  }
  return std::nullopt;
}

Features3d Tracker::Impl::frameFeatures(const RgbdFrame& frame) const {
  if (frame.depth.empty()) return Features3d{};
  return extractFeatures3d(grey_,
                           depthToMetres(frame.depth, frame.depth_scale, options_.keyframe_build.min_depth_m,
                                         options_.keyframe_build.max_depth_m),
                           camera_, options_.reloc_features);
}

bool Tracker::Impl::shortlisted() const {
  return options_.reloc_features.enabled && depthInTracking(mode_) &&
         replica_.map().numKeyframes() > static_cast<size_t>(options_.relocalise_shortlist);
}

double Tracker::Impl::relocaliseReachM(const RgbdFrame& frame) const {
  constexpr double kLastPoseErrorM = 1.0;  // what the last pose itself may be off by [m]
  // No last pose (a loaded map's start), or time gone back (a log replayed again): the
  // clock does not tell how far the camera went.
  if (options_.relocalise_max_speed_m_s <= 0.0 || !last_pose_utime_ || frame.utime < *last_pose_utime_) {
    return std::numeric_limits<double>::infinity();
  }
  const double lost_s = static_cast<double>(frame.utime - *last_pose_utime_) * 1e-6;
  return options_.relocalise_max_speed_m_s * lost_s + kLastPoseErrorM;
}

std::vector<KeyframeId> Tracker::Impl::relocalisationShortlist(const Features3d& features, double reach_m,
                                                               std::vector<KeyframeId>* by_words) {
  if (features.size() > 0) indexBags();
  const BowVector bag = features.size() > 0 ? projectVocabulary().bag(features.descriptors) : BowVector{};
  return rgbdslam::relocalisationShortlist(replica_.map(), bow_index_, bag, T_c_w_.inverse(), reach_m,
                                           static_cast<size_t>(options_.relocalise_shortlist),
                                           static_cast<size_t>(options_.reloc_features.candidates), by_words);
}

void Tracker::Impl::indexBags() {
  for (const auto& [id, keyframe] : replica_.map().keyframes()) {
    if (id < 0 || id > INT_MAX || bow_index_.contains(static_cast<int>(id))) continue;
    if (const KeyframeExtras* extras = extrasOf(id)) indexBag(id, *extras);
  }
}

void Tracker::Impl::indexBag(KeyframeId id, const KeyframeExtras& extras) {
  if (id < 0 || id > INT_MAX || bow_index_.contains(static_cast<int>(id))) return;
  bow_index_.add(static_cast<int>(id), extras.bag ? *extras.bag : projectVocabulary().bag(extras.features.descriptors));
}

std::optional<Attempt> Tracker::Impl::relocaliseByFeatures(const RgbdFrame& frame,
                                                           const std::vector<KeyframeId>& candidates, double reach_m,
                                                           std::optional<Features3d>* features, int extra_hot) {
  const FeatureRelocaliserOptions& o = options_.reloc_features;
  if (!o.enabled || !depthInTracking(mode_) || frame.depth.empty() || !anyExtras()) return std::nullopt;
  if (!*features) *features = frameFeatures(frame);
  const Features3d& current = **features;
  for (size_t k = 0; k < candidates.size() && k < static_cast<size_t>(o.candidates); ++k) {
    const KeyframeExtras* extras = extrasOf(candidates[k]);
    const Keyframe* keyframe = replica_.map().keyframe(candidates[k]);
    if (!extras || !keyframe) continue;
    const std::optional<FeaturePose> pose =
        poseFromFeatures(current, extras->features, keyframe->T_w_c, camera_, pose_options_, o);
    if (!pose) continue;
    // The features' pose is within the depth noise: near, as the last pose is.
    Attempt attempt = relocaliseFrom(RelocaliseStart{pose->T_w_c, keyframe->part, true, true}, frame, extra_hot);
    if (isLost(attempt) || attempt.quality < options_.quality.good) continue;
    // From a start centimetres off, one fine stage converges only part of the way (measured:
    // 2.5 cm left after a 5 s cover in the room, taken out over the next two frames as
    // jumps): once more from where it ended.
    for (int pass = 0; pass < kRelocaliseRefinePasses; ++pass) {
      saveOutcome(&outcome_);
      const Attempt again = trackFrom(attempt.T_c_w, frame, Coarse::kNever);
      if (isLost(again) || again.quality < kRelocaliseRefineKeep * attempt.quality) {
        restoreOutcome(outcome_);
        break;
      }
      attempt = again;
    }
    if (!withinReach(attempt.T_c_w, reach_m) || !integrityOf(attempt, frame).consistent()) continue;
    return attempt;
  }
  return std::nullopt;
}

bool Tracker::Impl::depthAidWanted(const Attempt& attempt, const RgbdFrame& frame) const {
  return options_.depth_align.enabled && depthInTracking(mode_) && !frame.depth.empty() &&
         anyExtras() &&
         (attempt.found < options_.depth_align.below_points || !poseFixed(attempt.uncertainty));
}

Attempt Tracker::Impl::alignWithDepth(const Attempt& attempt, const RgbdFrame& frame) {
  const DepthAlignmentOptions& o = options_.depth_align;
  anchors_.clear();
  appendKeyframeSurfaces(attempt.T_c_w.inverse(), &anchors_);
  if (depth_reference_) appendAnchors(depth_reference_->samples.get(), depth_reference_->T_w_c, &anchors_);
  if (anchors_.empty()) return attempt;
  // The found points (inliers of the fine stage) with their depth, and the surfaces.
  observations_.clear();
  std::vector<PointSlot*> found;
  for (PointSlot* slot : stage_) {
    if (!slot->found) continue;
    observations_.push_back({slot->point->p_w, slot->found_uv, slot->found_level,
                             pose_options_.use_depth ? depthAt(frame, slot->found_uv) : 0.0});
    found.push_back(slot);
  }
  const PointToPlaneResiduals planes(anchors_, frame, camera_, options_.pose.noise,
                                     options_.keyframe_build.min_depth_m,
                                     options_.keyframe_build.max_depth_m, o.max_incidence_deg);
  // From the attempt's pose, and from the motion model's without the small-blurry-image
  // rotation: an image that shows nothing (a plain wall, the lights out) misleads that
  // rotation estimate, and the attempt's few points may not have corrected it.
  PoseOptimizerResult fit =
      optimisePose(camera_, attempt.T_c_w, observations_, pose_options_, &inliers_, &planes, priorOrNull());
  // The information the surfaces really give (honestInformation) replaces theirs in the fit's.
  Eigen::Matrix<double, 6, 6> surfaces_excess =
      fit.extra_information - planes.honestInformation(fit.extra_information, o.effective_samples, fit.inliers_extra);
  const SE3 velocity_start = SE3::exp(options_.motion.velocity_damping * velocity_) * T_c_w_;
  std::vector<uint8_t> other_inliers;
  const PoseOptimizerResult other =
      optimisePose(camera_, velocity_start, observations_, pose_options_, &other_inliers, &planes,
                   priorOrNull());
  if (other.ok && (!fit.ok || other.inliers_extra + other.inliers_2d > fit.inliers_extra + fit.inliers_2d)) {
    fit = other;
    inliers_.swap(other_inliers);
    surfaces_excess = other.extra_information -
                      planes.honestInformation(other.extra_information, o.effective_samples, other.inliers_extra);
  }
  if (!fit.ok || fit.inliers_extra < o.min_inliers ||
      fit.inliers_extra < o.min_inlier_ratio * fit.extra_residuals) {
    return attempt;
  }
  // A vehicle does not jump: a fit far from the motion model's prediction found another
  // basin of the surfaces, not the pose.
  const SE3 predicted_w_c = velocity_start.inverse(), fitted_w_c = fit.T_c_w.inverse();
  if ((fitted_w_c.translation() - predicted_w_c.translation()).norm() > o.max_step_m ||
      fitted_w_c.rotation().angularDistance(predicted_w_c.rotation()) > o.max_step_deg * M_PI / 180.0) {
    return attempt;
  }
  Attempt aligned = attempt;
  aligned.T_c_w = fit.T_c_w;
  aligned.uncertainty = poseUncertainty(fit.information - surfaces_excess);
  aligned.information = fit.information - surfaces_excess;
  aligned.depth_aided = true;
  aligned.found = 0;
  depths_.clear();
  for (size_t i = 0; i < found.size(); ++i) {
    found[i]->found = inliers_[i] != 0;
    aligned.found += found[i]->found;
    if (found[i]->found) depths_.push_back((fit.T_c_w * found[i]->point->p_w).z());
  }
  // Too few points for their median depth: the surfaces' (the keyframe rule's scale).
  if (depths_.size() < 3) {
    depths_.clear();
    for (const SurfaceAnchor& a : anchors_) depths_.push_back((fit.T_c_w * a.p_w).z());
  }
  aligned.median_depth_m = median(&depths_);
  return aligned;
}

void Tracker::Impl::appendKeyframeSurfaces(const SE3& T_w_c, std::vector<SurfaceAnchor>* anchors) {
  const size_t wanted = static_cast<size_t>(options_.depth_align.keyframes);
  size_t used = 0;
  for (KeyframeId id : replica_.map().nearestKeyframesInPart(T_w_c, 4 * wanted, projection_part_)) {
    if (used >= wanted) break;
    const KeyframeExtras* extras = extrasOf(id);
    if (!extras || extras->surface.empty()) continue;
    appendAnchors(extras->surface, replica_.map().keyframe(id)->T_w_c, anchors);
    ++used;
  }
}

void Tracker::Impl::startDeadReckoning() {
  if (!options_.relocalise_dead_reckoning || !options_.depth_align.enabled || !depthInTracking(mode_)) {
    dead_reckoning_.reset();
    return;
  }
  if (!dead_reckoning_) {
    dead_reckoning_.emplace(camera_, options_.depth_align, pose_options_, options_.keyframe_build.min_depth_m,
                            options_.keyframe_build.max_depth_m, options_.relocalise_reckoning_sigma_m,
                            options_.relocalise_reckoning_sigma_deg * M_PI / 180.0);
  }
  dead_reckoning_->start(motion_prior_);
}

void Tracker::Impl::stepDeadReckoning(const RgbdFrame& frame) {
  if (!dead_reckoning_ || frame.depth.empty()) return;
  const std::optional<SE3> predicted = dead_reckoning_->predict(frame.utime);
  if (!predicted) return;
  reckoning_anchors_.clear();
  appendKeyframeSurfaces(predicted->inverse(), &reckoning_anchors_);
  frames_reckoned_ += dead_reckoning_->step(frame, reckoning_anchors_);
}

SE3 Tracker::Impl::lostPoseGuess(int64_t utime, int coast_frames) const {
  if (dead_reckoning_) {
    // Coasted past the last frame held for at most relocalise_coast_frames, as from the last
    // pose: frames counted since the loss (passed ones too) give the frames' interval.
    const double frame_s = lost_frames_ > 0 && last_pose_utime_ && utime > *last_pose_utime_
                               ? static_cast<double>(utime - *last_pose_utime_) * 1e-6 / lost_frames_
                               : 0.0;
    const int coast = std::min(coast_frames, options_.relocalise_coast_frames);
    if (const std::optional<SE3> reckoned = dead_reckoning_->poseAt(utime, coast * frame_s)) return *reckoned;
  }
  return SE3::exp(static_cast<double>(coast_frames) * lost_velocity_) * T_c_w_;
}

void Tracker::Impl::rememberKeyframe(const Keyframe& keyframe) {
  if (!depthInTracking(mode_)) return;
  if (!options_.depth_align.enabled && !options_.reloc_features.enabled) return;
  if (2 * (replica_.map().numKeyframes() + 1) >= static_cast<size_t>(options_.relocalise_shortlist)) {
    warmUpVocabulary();
  }
  // The job owns what it reads: the images' buffers (shared, never written again) and copies
  // of the options, so that neither the keyframe nor an option change can reach it.
  extras_[keyframe.id] = keyframe_worker_.submit(
      [depth = keyframe.depth, grey = keyframe.grey(), camera = camera_, noise = options_.pose.noise,
       align = options_.depth_align, features = options_.reloc_features, ready = vocabulary_ready_] {
        KeyframeExtras extras;
        const cv::Mat metres = depth.metres();
        if (align.enabled) extras.surface = sampleSurface(metres, camera, noise, align);
        if (features.enabled) extras.features = extractFeatures3d(grey, metres, camera, features);
        if (features.enabled && ready->load()) extras.bag = projectVocabulary().bag(extras.features.descriptors);
        return extras;
      });
}

void Tracker::Impl::warmUpVocabulary() {
  if (!options_.reloc_features.enabled || !depthInTracking(mode_) || vocabulary_warmup_.valid()) return;
  vocabulary_warmup_ = std::async(std::launch::async, [ready = vocabulary_ready_] {
    projectVocabulary();
    ready->store(true);
    // The training's frames (~20 MB) are freed by now. The suite's processes run on jemalloc
    // (procs/common/allocator.h), which gives such pages back to the system from background
    // threads of its own within its decay time (10 s), so nothing is trimmed here.
  });
}

// A new reference once the camera has moved on from the last one; none once the points hold
// the pose again (a stale reference would be a second, older map in the fit).
void Tracker::Impl::updateDepthReference(const Attempt& attempt, const RgbdFrame& frame) {
  const DepthAlignmentOptions& o = options_.depth_align;
  if (!attempt.depth_aided || o.reference_step_m <= 0.0) {
    depth_reference_.reset();
    return;
  }
  const SE3 T_w_c = T_c_w_.inverse();
  if (depth_reference_ &&
      (T_w_c.translation() - depth_reference_->T_w_c.translation()).norm() < o.reference_step_m &&
      T_w_c.rotation().angularDistance(depth_reference_->T_w_c.rotation()) < o.reference_step_deg * M_PI / 180.0) {
    return;
  }
  const cv::Mat depth = depthToMetres(frame.depth, frame.depth_scale, options_.keyframe_build.min_depth_m,
                                      options_.keyframe_build.max_depth_m);
  depth_reference_ = DepthReference{
      keyframe_worker_.submit([depth, camera = camera_, noise = options_.pose.noise, align = o] {
        return sampleSurface(depth, camera, noise, align);
      }),
      T_w_c};
}

const KeyframeExtras* Tracker::Impl::extrasOf(KeyframeId id) {
  const auto extras = extras_.find(id);
  if (extras != extras_.end()) return &extras->second.get();
  if (!store_ || !store_->has(id, KeyframeStore::Kind::kExtras)) return nullptr;
  for (auto& [cached_id, cached] : extras_cache_) {
    if (cached_id == id) return &cached;
  }
  const Expected<std::vector<uint8_t>> bytes = store_->get(id, KeyframeStore::Kind::kExtras);
  if (!bytes) return nullptr;  // the storage failed (counted by the store)
  std::optional<KeyframeExtras> decoded = decodeExtras(*bytes);
  if (!decoded) return nullptr;  // cannot happen with CRC-checked bytes this process wrote
  if (extras_cache_.size() >= kExtrasCached) extras_cache_.pop_front();  // references to the rest stay
  extras_cache_.emplace_back(id, std::move(*decoded));
  return &extras_cache_.back().second;
}

bool Tracker::Impl::anyExtras() const {
  return !extras_.empty() || (store_ && store_->entries(KeyframeStore::Kind::kExtras) > 0);
}

void Tracker::Impl::setAnchor() {
  const Keyframe* best = nullptr;
  int best_count = 0;
  std::unordered_map<const Keyframe*, int> found_from;
  for (const PointSlot* slot : stage_) {
    if (!slot->found || !slot->source) continue;
    const int count = ++found_from[slot->source];
    if (count > best_count || (count == best_count && slot->source->id > best->id)) {
      best = slot->source;
      best_count = count;
    }
  }
  if (!best) {
    const std::vector<KeyframeId> nearest = replica_.map().nearestKeyframesInPart(T_c_w_.inverse(), 1, part_);
    if (!nearest.empty()) best = replica_.map().keyframe(nearest.front());
  }
  if (best) anchor_ = Anchor{best->id, best->T_w_c};
}

// The anchor keyframe is about to be culled: the nearest keyframe that stays takes its place,
// with its pose before this update, so that a correction arriving with the cull is followed.
void Tracker::Impl::reanchorBeforeCull(const std::vector<KeyframeId>& removed) {
  if (!anchor_ || std::find(removed.begin(), removed.end(), anchor_->id) == removed.end()) return;
  anchor_.reset();
  const Map& map = replica_.map();
  for (KeyframeId id : map.nearestKeyframesInPart(T_c_w_.inverse(), map.numKeyframes(), part_)) {
    if (std::find(removed.begin(), removed.end(), id) != removed.end()) continue;
    anchor_ = Anchor{id, map.keyframe(id)->T_w_c};
    return;
  }
}

void Tracker::Impl::followMapCorrection(bool joined) {
  if (!anchor_) return;
  const Keyframe* keyframe = replica_.map().keyframe(anchor_->id);
  if (!keyframe) {
    anchor_.reset();
    return;
  }
  // (The rigid motion of the last frame's found points was tried instead: corridor 900's
  // ATE went to 1.03 m, a few ill-spread points giving wild rotations.)
  const SE3 correction = keyframe->T_w_c * anchor_->T_w_k.inverse();  // old world -> new, near the camera
  anchor_->T_w_k = keyframe->T_w_c;
  const SE3 old_pose = T_c_w_.inverse();
  const SE3 old_published = published(old_pose);
  const SE3 new_pose = correction * old_pose;
  if (options_.follow_map_corrections || joined) T_c_w_ = new_pose.inverse();
  // The prior follows the map either way: the next fit finds the pose in the moved map, and
  // the map's move is not the vehicle's.
  motion_prior_.moveWorld(correction);
  if (depth_reference_) depth_reference_->T_w_c = correction * depth_reference_->T_w_c;
  if (dead_reckoning_) dead_reckoning_->moveWorld(correction);
  offset_.position = old_published.translation() - new_pose.translation();
  offset_.rotation = (old_published.rotation() * new_pose.rotation().inverse()).normalized();
}

void Tracker::Impl::publish(TrackResult* result, int64_t utime) {
  const double dt_s = last_utime_ ? std::clamp((utime - *last_utime_) * 1e-6, 0.0, 1.0) : 0.0;
  last_utime_ = utime;
  const double rate_m = options_.correction_rate_m_s, rate_rad = options_.correction_rate_deg_s * M_PI / 180.0;
  const double distance = offset_.position.norm();
  if (rate_m <= 0.0 || distance <= rate_m * dt_s) {
    offset_.position.setZero();
  } else {
    offset_.position *= 1.0 - rate_m * dt_s / distance;
  }
  const double angle = Eigen::AngleAxisd(offset_.rotation).angle();
  if (rate_rad <= 0.0 || angle <= rate_rad * dt_s) {
    offset_.rotation.setIdentity();
  } else {
    offset_.rotation = Eigen::Quaterniond::Identity().slerp(1.0 - rate_rad * dt_s / angle, offset_.rotation);
  }
  result->pose.map_T_w_c = result->pose.T_w_c;
  result->pose.part = part_;
  if (result->status != TrackStatus::kTracked && result->status != TrackStatus::kRelocalised &&
      result->status != TrackStatus::kLost) {
    published_history_.clear();
    return;  // no pose (initialised: keyframe 0 is the world, no correction yet)
  }
  if (const Keyframe* anchor = anchor_ ? replica_.map().keyframe(anchor_->id) : nullptr) {
    result->anchor = anchor->id;
    result->T_anchor_c = anchor->T_w_c.inverse() * result->pose.map_T_w_c;
  }
  result->pose.T_w_c = published(result->pose.T_w_c);
  holdStepAgainstMotion(result, utime);
  result->correction_m = offset_.position.norm();
  result->correction_deg = Eigen::AngleAxisd(offset_.rotation).angle() * 180.0 / M_PI;
}

void Tracker::Impl::holdStepAgainstMotion(TrackResult* result, int64_t utime) {
  if (result->status == TrackStatus::kLost) {
    published_history_.clear();
    return;
  }
  const Vec3 position = result->pose.T_w_c.translation();
  const double limit = options_.quality.good_step_m;
  if (result->pose.state == TrackingState::kTracking && mode_ != SlamMode::kMono && limit > 0.0 &&
      published_history_.size() == 2) {
    const auto& [t1, p1] = published_history_[0];
    const auto& [t2, p2] = published_history_[1];
    if (utime > t1 && t1 > t2) {
      const Vec3 extrapolated = p1 + (p1 - p2) * (static_cast<double>(utime - t1) / static_cast<double>(t1 - t2));
      if ((position - extrapolated).norm() > limit) result->pose.state = TrackingState::kDodgy;
    }
  }
  published_history_.insert(published_history_.begin(), {utime, position});
  if (published_history_.size() > 2) published_history_.pop_back();
}

int Tracker::Impl::cornerCount() const {
  size_t count = 0;
  for (const LevelCorners& level : corners_) count += level.all.size();
  return static_cast<int>(std::min<size_t>(count, INT_MAX));
}

std::string Tracker::Impl::lossReason(const Attempt& attempt) const {
  if (attempt.searched == 0) return "no map point in view";
  if (attempt.found < options_.quality.min_points_tracked) return std::to_string(attempt.found) + " points found";
  if (attempt.quality < options_.quality.lost) return "quality " + std::to_string(attempt.quality).substr(0, 4);
  return "the points found do not fix the pose";
}

TrackResult Tracker::Impl::lostResult(const Attempt& attempt, std::string reason, bool inconsistent) {
  state_ = TrackingState::kLost;
  lost_velocity_ = velocity_;
  uncertain_frames_ = 0;
  lost_frames_ = 1;  // this frame: the first relocalisation is two frames past the last pose
  failed_relocalisations_ = 0;
  velocity_.setZero();
  startDeadReckoning();  // from the motion prior as it was at the last pose
  motion_prior_.clear();
  last_quality_ = 0.0;
  depth_reference_.reset();
  TrackResult result;
  result.status = TrackStatus::kLost;
  result.pose.state = TrackingState::kLost;
  result.pose.T_w_c = T_c_w_.inverse();
  result.pose.points_tracked = attempt.found;
  result.pose.quality = attempt.quality;
  result.lost_reason = std::move(reason);
  frame_inconsistent_ = frame_inconsistent_ || inconsistent;
  return result;
}

// The coarse stage is for large image motion (PTAM: fast motion): the median displacement
// of the visible points (projected at the start pose, slot->uv) from where the last pose
// puts them.
bool Tracker::Impl::coarseWanted(const SE3& T_c_w_start) {
  if (options_.coarse.min_motion_px <= 0.0 || visible_.empty()) return true;
  if (replica_.map().numKeyframes() == 0) return true;
  const SE3 T_last_start = T_c_w_ * T_c_w_start.inverse();
  displacements_.clear();
  for (const PointSlot* slot : visible_) {
    const auto uv_last = camera_.project(T_last_start * slot->p_c);
    if (uv_last) displacements_.push_back((*uv_last - slot->uv).norm());
  }
  if (displacements_.empty()) return true;
  return median(&displacements_) >= options_.coarse.min_motion_px;
}

bool Tracker::Impl::isLost(const Attempt& attempt) const {
  // Held by depth and points together: what counts is whether they fix the pose.
  if (attempt.depth_aided) return !poseFixed(attempt.uncertainty);
  return attempt.searched == 0 || attempt.quality < options_.quality.lost ||
         attempt.found < options_.quality.min_points_tracked || !poseFixed(attempt.uncertainty);
}

bool Tracker::Impl::poseFixed(const PoseUncertainty& uncertainty) const {
  return uncertainty.translation_m <= options_.quality.max_pose_sigma_m &&
         uncertainty.rotation_rad <= options_.quality.max_pose_sigma_deg * M_PI / 180.0;
}

// Whether new points from depth, measured in the frame that would become keyframe 0 (world
// = camera), fix its pose: the pose fit at the identity gives the information matrix.
bool Tracker::Impl::constrainsPose(const std::vector<NewPoint>& points, KeyframeId id, const SE3& T_c_w) const {
  std::vector<PoseObservation> observations;
  for (const NewPoint& np : points) {
    if (!isProvisionalPointOf(np.point.id, id)) break;
    observations.push_back({np.point.p_w, np.measurement.uv, np.measurement.level,
                            options_.pose.use_depth ? np.measurement.depth : 0.0});
  }
  const PoseOptimizerResult fit = optimisePose(camera_, T_c_w, observations, pose_options_);
  return fit.ok && poseFixed(poseUncertainty(fit.information));
}

// Takes the attempt's pose, updates the motion model and point statistics, and decides
// about a keyframe.
bool Tracker::Impl::preciseForFlight(const PoseUncertainty& uncertainty) const {
  const double independent_steps = 3.0 * std::sqrt(2.0);  // 3 sigma of a difference of two
  const QualityOptions& q = options_.quality;
  const bool metric = mode_ != SlamMode::kMono;
  return (!metric || q.good_step_m <= 0.0 || independent_steps * uncertainty.translation_m <= q.good_step_m) &&
         (q.good_step_deg <= 0.0 || independent_steps * uncertainty.rotation_rad * 180.0 / M_PI <= q.good_step_deg);
}

TrackResult Tracker::Impl::accept(const Attempt& attempt, const RgbdFrame& frame,
                                  TrackingState state, std::optional<TrackingState> grade) {
  const TrackingState keyframe_grade = grade.value_or(state);
  if (state != TrackingState::kRelocalised) velocity_ = (attempt.T_c_w * T_c_w_.inverse()).log();
  if (state == TrackingState::kRelocalised) motion_prior_.reset(frame.utime, attempt.T_c_w, attempt.information);
  else motion_prior_.update(frame.utime, attempt.T_c_w, attempt.information);
  T_c_w_ = attempt.T_c_w;
  last_pose_utime_ = frame.utime;
  last_quality_ = attempt.quality;
  state_ = state == TrackingState::kRelocalised ? TrackingState::kTracking : state;
  updateDepthReference(attempt, frame);
  // A relocalised pose vouches for nothing yet: hidden points are left out from the frame
  // after the next pose tracked from the motion's prediction (trackFrame).
  const bool vouches = state != TrackingState::kRelocalised;
  depth_agreeing_found_ = 0;
  for (PointSlot* slot : stage_) {
    if (slot->depth_verdict != DepthVerdict::kUnchecked) {
      depth_agreeing_found_ += vouches && slot->found && slot->depth_verdict == DepthVerdict::kAgrees;
      slot->point->depth_record.add(slot->depth_verdict, (T_c_w_ * slot->point->p_w).z());
      slot->depth_verdict = DepthVerdict::kUnchecked;
    }
    if (!slot->searched) continue;
    ++slot->point->times_projected;
    if (slot->found) ++slot->point->times_found;
  }
  setAnchor();
  TrackResult result;
  result.status = state == TrackingState::kRelocalised ? TrackStatus::kRelocalised : TrackStatus::kTracked;
  result.pose.state = state;
  result.pose.T_w_c = T_c_w_.inverse();
  result.pose.points_tracked = attempt.found;
  result.pose.quality = attempt.quality;
  result.depth_aided = attempt.depth_aided;
  result.pose_sigma_m = attempt.uncertainty.translation_m;
  result.pose_sigma_deg = attempt.uncertainty.rotation_rad * 180.0 / M_PI;
  ++frames_since_keyframe_;
  const double uncertain_sigma_m = options_.keyframes.uncertain_pose_sigma_m;
  uncertain_frames_ = uncertain_sigma_m > 0.0 && result.pose_sigma_m > uncertain_sigma_m ? uncertain_frames_ + 1 : 0;
  // A frame held by depth makes a keyframe only where it offers corners for new points: one
  // without would carry only its depth-held pose into the map, and the next frames, aligned
  // to it, would inherit that error (measured on the office: a 5 cm step when such a
  // keyframe became one of the two aligned against).
  const bool corners_for_points = !attempt.depth_aided || cornerCount() >= options_.keyframes.few_points;
  const bool keyframe_allowed =
      corners_for_points &&
      (keyframe_grade == TrackingState::kTracking ||
       (keyframe_grade == TrackingState::kDodgy && options_.keyframes_while_dodgy &&
        depthPointsAllowed(mode_, next_keyframe_id_)));
  const KeyframePolicyInput input{keyframe_allowed, frames_since_keyframe_,
                                  attempt.median_depth_m, result.pose.T_w_c, attempt.found,
                                  depthPointsAllowed(mode_, next_keyframe_id_), cornerCount(),
                                  uncertain_frames_, part_};
  if (keyframes_allowed_ && shouldAddKeyframe(replica_.map(), input, options_.keyframes)) {
    pending_keyframe_ = PendingKeyframe{frame.utime, result.pose.T_w_c, foundMeasurements(frame),
                                        frame.depth.empty() ? cv::Mat() : frame.depth.clone(), frame.depth_scale};
    if (anchor_) pending_keyframe_->anchor = anchor_->id, pending_keyframe_->T_w_anchor = anchor_->T_w_k;
  }
  return result;
}

// ---------------------------------------------------------------------------------------
// Tracking from a start pose: projection, coarse stage, fine stage

void Tracker::Impl::saveOutcome(std::vector<SlotOutcome>* outcome) const {
  outcome->clear();
  for (PointSlot* slot : stage_) {
    outcome->push_back({slot, slot->searched, slot->found, slot->found_uv, slot->found_level});
  }
}

// Makes stage_ and the slots' search flags those of the saved attempt again.
Attempt Tracker::Impl::betterOf(const Attempt& attempt, const SE3& start, const RgbdFrame& frame,
                                Coarse coarse) {
  saveOutcome(&outcome_);
  const Attempt other = trackFrom(start, frame, coarse);
  if (other.quality > attempt.quality) return other;
  restoreOutcome(outcome_);
  return attempt;
}

void Tracker::Impl::restoreOutcome(const std::vector<SlotOutcome>& outcome) {
  for (PointSlot& slot : replica_.slots()) slot.searched = slot.found = false;
  stage_.clear();
  for (const SlotOutcome& o : outcome) {
    o.slot->searched = o.searched;
    o.slot->found = o.found;
    o.slot->found_uv = o.found_uv;
    o.slot->found_level = o.found_level;
    stage_.push_back(o.slot);
  }
}

Attempt Tracker::Impl::trackFrom(const SE3& T_c_w_start, const RgbdFrame& frame, Coarse coarse) {
  for (PointSlot& slot : replica_.slots()) slot.searched = slot.found = false;
  SE3 T_c_w = T_c_w_start;
  projectAll(T_c_w);
  dropHidden(frame);
  stage_.clear();
  for (PointSlot* slot : visible_) {
    if (slot->search_level >= options_.coarse.min_level) stage_.push_back(slot);
  }
  bool did_coarse = false;
  coarse_possible_ = static_cast<int>(stage_.size()) >= options_.coarse.min_points;
  if (coarse != Coarse::kNever && coarse_possible_ &&
      (coarse == Coarse::kAlways || coarseWanted(T_c_w_start))) {
    did_coarse = true;
    selectSubset(&stage_, options_.coarse.max_points);
    T_c_w = runStage(stage_, T_c_w, options_.coarse.radius_px, frame, false);
    for (PointSlot* slot : stage_) slot->searched = slot->found = false;
    projectAll(T_c_w);
    dropHidden(frame);
  }
  stage_ = visible_;
  selectSubset(&stage_, options_.fine.max_points);
  T_c_w = runStage(stage_, T_c_w, options_.fine.radius_px, frame, true);

  Attempt attempt;
  attempt.T_c_w = T_c_w;
  attempt.uncertainty = poseUncertainty(fine_information_);
  attempt.information = fine_information_;
  attempt.did_coarse = did_coarse;
  depths_.clear();
  int reliable_searched = 0, reliable_found = 0;
  for (PointSlot* slot : stage_) {
    attempt.searched += slot->searched;
    attempt.found += slot->found;
    if (slot->found) depths_.push_back((T_c_w * slot->point->p_w).z());
    if (slot->searched && isReliable(*slot->point)) {
      ++reliable_searched;
      reliable_found += slot->found;
    }
  }
  if (reliable_searched > 0) {
    attempt.quality = static_cast<double>(reliable_found) / reliable_searched;
  } else if (attempt.searched > 0) {
    attempt.quality = static_cast<double>(attempt.found) / attempt.searched;
  }
  attempt.median_depth_m = median(&depths_);
  return attempt;
}

void Tracker::Impl::projectAll(const SE3& T_c_w) {
  makeKeyframeViews(replica_.map(), T_c_w, &views_);
  visible_.clear();
  points_in_view_.assign(views_.size(), 0);
  for (PointSlot& slot : replica_.slots()) {
    if (slot.source && slot.source->part != projection_part_) continue;
    if (!projectPoint(camera_, T_c_w, views_, options_.projection, &slot)) continue;
    visible_.push_back(&slot);
    ++points_in_view_[static_cast<size_t>(slot.point->source_keyframe)];
  }
  cold_count_ = ColdCount{T_c_w, projection_part_, true};
}

// The points of cold keyframes have no slot (map_replica.h); those in view at the last
// projection count for their keyframes, so that the local map thaws the keyframes the camera
// came back to. Only keyframes whose points' bounding sphere may be in view are looked at.
// Counted once, when wanted: at every projection (one or two a frame: two when the coarse
// stage runs) this was 1.9-3.1 ms a projection late in the 10-minute flight (7 000-16 700
// points of 57-134 cold keyframes), on the pose's path. Now a tracked frame's count is made
// after its pose (finishFrame's updateLocalMap); while lost, a candidate's thaws count the
// previous candidate's projection (relocaliseFrom); on a map within the window
// (updateLocalMap returns first) it is made, if at all, by the next change to the replica
// (a map version, a keyframe).
void Tracker::Impl::countColdInView() {
  if (!cold_count_.pending) return;
  cold_count_.pending = false;
  const SE3& T_c_w = cold_count_.T_c_w;
  for (const auto& [id, keyframe] : replica_.map().keyframes()) {
    const auto kf = static_cast<size_t>(id);
    if (kf >= views_.size() || !views_[kf].cold || keyframe->part != cold_count_.part) continue;
    const MapReplica::Bounds bounds = replica_.boundsOf(id);
    if (bounds.radius < 0.0 || !sphereMayBeInView(camera_, T_c_w, bounds.centre, bounds.radius, options_.projection)) {
      continue;
    }
    replica_.forEachPosition(id, [&](const Vec3& p_w) {
      if (inView(camera_, T_c_w, p_w, options_.projection)) ++points_in_view_[kf];
    });
  }
}

void Tracker::Impl::dropHidden(const RgbdFrame& frame) {
  if (!drop_hidden_ || !options_.occlusion.enabled || !depthInTracking(mode_) || frame.depth.empty()) return;
  const KeyframeBuildOptions& range = options_.keyframe_build;
  visible_.erase(std::remove_if(visible_.begin(), visible_.end(),
                                [&](const PointSlot* slot) {
                                  return hiddenInDepth(slot->p_c, slot->uv, frame, options_.pose.noise,
                                                       range.min_depth_m, range.max_depth_m, options_.occlusion);
                                }),
                 visible_.end());
}

// Searches the slots and updates the pose by Gauss-Newton on the found ones. With
// mark_inliers, found points that the robust fit rejected are marked not found.
SE3 Tracker::Impl::runStage(const std::vector<PointSlot*>& slots, const SE3& T_c_w, int radius_px,
                            const RgbdFrame& frame, bool mark_inliers) {
  searchPoints(slots, pyramid_, corners_, radius_px, options_.search);
  observations_.clear();
  std::vector<PointSlot*> found;
  for (PointSlot* slot : slots) {
    if (!slot->found) continue;
    const double depth = pose_options_.use_depth ? depthAt(frame, slot->found_uv) : 0.0;
    observations_.push_back({slot->point->p_w, slot->found_uv, slot->found_level, depth});
    found.push_back(slot);
  }
  PoseOptimizerResult fit =
      optimisePose(camera_, T_c_w, observations_, pose_options_, &inliers_, nullptr, priorOrNull());
  if (fit.ok && prior_ && mark_inliers && !options_.motion_prior.in_final_fit) {
    // The prior chose the matches; the points alone place the camera in the map they
    // belong to (motion_prior.h).
    inlier_observations_.clear();
    inlier_index_.clear();
    for (size_t i = 0; i < found.size(); ++i) {
      if (!inliers_[i]) continue;
      inlier_observations_.push_back(observations_[i]);
      inlier_index_.push_back(i);
    }
    const PoseOptimizerResult free_fit =
        optimisePose(camera_, fit.T_c_w, inlier_observations_, pose_options_, &inlier_kept_);
    if (free_fit.ok) {
      fit = free_fit;
      std::fill(inliers_.begin(), inliers_.end(), 0);
      for (size_t k = 0; k < inlier_index_.size(); ++k) inliers_[inlier_index_[k]] = inlier_kept_[k];
    }
  }
  if (mark_inliers) fine_information_ = fit.information;
  if (!fit.ok) return T_c_w;
  if (mark_inliers) {
    for (size_t i = 0; i < found.size(); ++i) found[i]->found = inliers_[i] != 0;
  }
  return fit.T_c_w;
}

void Tracker::Impl::selectSubset(std::vector<PointSlot*>* slots, int max_count) {
  if (static_cast<int>(slots->size()) <= max_count) return;
  // Partial Fisher-Yates: the first max_count entries become a uniform random subset.
  for (int i = 0; i < max_count; ++i) {
    std::uniform_int_distribution<size_t> pick(static_cast<size_t>(i), slots->size() - 1);
    std::swap((*slots)[static_cast<size_t>(i)], (*slots)[pick(rng_)]);
  }
  slots->resize(static_cast<size_t>(max_count));
}

double Tracker::Impl::depthAt(const RgbdFrame& frame, const Eigen::Vector2d& uv) const {
  if (frame.depth.empty() || frame.depth.type() != CV_16UC1) return 0.0;
  const int u = static_cast<int>(std::lround(uv.x())), v = static_cast<int>(std::lround(uv.y()));
  if (u < 0 || v < 0 || u >= frame.depth.cols || v >= frame.depth.rows) return 0.0;
  const uint16_t raw = frame.depth.at<uint16_t>(v, u);
  const double d = raw / frame.depth_scale;
  if (raw == 0 || d < options_.keyframe_build.min_depth_m || d > options_.keyframe_build.max_depth_m) {
    return 0.0;
  }
  return d;
}

// ---------------------------------------------------------------------------------------
// Keyframes

std::vector<Measurement> Tracker::Impl::foundMeasurements(const RgbdFrame& frame) const {
  std::vector<Measurement> measurements;
  for (const PointSlot* slot : stage_) {
    if (!slot->found) continue;
    measurements.push_back({slot->point->id, slot->found_uv, slot->found_level,
                            depthAt(frame, slot->found_uv)});
  }
  return measurements;
}

KeyframeData Tracker::Impl::addKeyframe(PendingKeyframe pending) {
  KeyframeData data;
  data.utime = pending.utime;
  data.map_id = map_id_;
  data.id = next_keyframe_id_++;
  data.T_w_c = pending.T_w_c;
  data.grey = grey_.clone();
  data.depth = std::move(pending.depth);
  data.depth_scale = pending.depth_scale;
  data.measurements = std::move(pending.measurements);
  data.anchor = pending.anchor;
  data.T_w_anchor = pending.T_w_anchor;
  std::unique_ptr<Keyframe> keyframe = makeKeyframe(data, options_.keyframe_build);
  keyframe->part = part_;
  std::vector<NewPoint> points;
  if (depthPointsAllowed(mode_, data.id)) {
    points = createPointsFromDepth(*keyframe, camera_, options_.depth_points,
                                   provisionalPointId(data.id, 0));
  }
  rememberKeyframe(*keyframe);
  keyframe->releaseMappingData();  // the mapper gets 'data'; the replica tracks with the pyramid
  countColdInView();  // before the replica changes
  replica_.addKeyframe(std::move(keyframe));
  for (const NewPoint& np : points) {
    if (!isProvisionalPointOf(np.point.id, data.id)) break;
    replica_.addProvisionalPoint(np);
    data.measurements.push_back(np.measurement);
    data.new_points.push_back(np.point.data());
  }
  frames_since_keyframe_ = 0;
  uncertain_frames_ = 0;
  return data;
}

// ---------------------------------------------------------------------------------------

Tracker::Tracker(const PinholeCamera& camera, const TrackerOptions& options, SlamMode mode,
                 int64_t map_id)
    : impl_(std::make_unique<Impl>(camera, options, mode, map_id)) {}
Tracker::~Tracker() = default;
TrackResult Tracker::track(const RgbdFrame& frame) { return impl_->track(frame); }
TrackResult Tracker::trackPose(const RgbdFrame& frame) { return impl_->trackPose(frame); }
std::optional<KeyframeData> Tracker::finishFrame(bool real_time) { return impl_->finishFrame(real_time); }
TrackResult Tracker::passLost(const RgbdFrame& frame) { return impl_->passLost(frame); }
void Tracker::countPassedFrames(int frames) { impl_->countPassedFrames(frames); }
bool Tracker::followLost(const RgbdFrame& frame) { return impl_->followLost(frame); }
bool Tracker::lost() const { return impl_->lost(); }
long Tracker::rejoins() const { return impl_->rejoins(); }
long Tracker::rejoinTries() const { return impl_->rejoinTries(); }
long Tracker::framesReckoned() const { return impl_->framesReckoned(); }
std::string Tracker::frameError(const RgbdFrame& frame) const { return impl_->frameError(frame); }
bool Tracker::applyMap(const MapUpdate& update, bool defer_cold) { return impl_->applyMap(update, defer_cold); }
bool Tracker::applyDeferredMap(size_t max_entries) { return impl_->applyDeferredMap(max_entries); }
bool Tracker::hasDeferredMapWork() const { return impl_->replica().hasDeferred(); }
const Map& Tracker::map() const { return impl_->map(); }
size_t Tracker::numPoints() const { return impl_->replica().numPoints(); }
size_t Tracker::pointsOnStorage() const { return impl_->replica().storedPoints(); }
int64_t Tracker::pointsLostOnStorage() const { return impl_->replica().pointsLost(); }
void Tracker::reset() { impl_->reset(); }
void Tracker::load(const LoadedMap& loaded, bool add_keyframes) { impl_->load(loaded, add_keyframes); }
const KeyframeStore* Tracker::keyframeStore() const { return impl_->keyframeStore(); }
const Status& Tracker::keyframeStoreStatus() const { return impl_->keyframeStoreStatus(); }

}  // namespace rgbdslam
