// The mapper's flow (mapper.h): in-order integration, epipolar points, local and global
// bundle adjustment, re-finding of new points and culling. The building blocks live in
// epipolar_search.cpp, data_association.cpp, ba_problem.cpp and map_maintenance.cpp.
#include "rgbdslam/mapping/mapper.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <optional>
#include <set>
#include <unordered_map>
#include <utility>

#include "rgbdslam/mapping/ba_problem.h"
#include "rgbdslam/mapping/data_association.h"
#include "rgbdslam/mapping/epipolar_search.h"
#include "rgbdslam/image/patch.h"
#include "rgbdslam/mapping/loop_closer.h"
#include "rgbdslam/mapping/map_maintenance.h"

namespace rgbdslam {

const char* toString(MapperResult::Status status) {
  switch (status) {
    case MapperResult::Status::kIntegrated: return "integrated";
    case MapperResult::Status::kBadKeyframe: return "bad_keyframe";
  }
  return "?";
}

namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

bool interrupted(const std::atomic<bool>* interrupt) { return interrupt && interrupt->load(); }

bool usableResult(const BaResult& r) {
  return r.status == BaResult::Status::kConverged || r.status == BaResult::Status::kMaxIterations ||
         r.status == BaResult::Status::kInterrupted;
}

void updateMedianDepth(const Map& map, Keyframe* kf) {
  std::vector<double> depths;
  const SE3 T_c_w = kf->T_c_w();
  for (const auto& [pid, m] : kf->measurements()) {
    if (const MapPoint* p = map.point(pid)) {
      const double z = (T_c_w * p->p_w).z();
      if (z > 0) depths.push_back(z);
    }
  }
  if (depths.empty()) return;
  std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
  kf->median_depth = depths[depths.size() / 2];
}

}  // namespace

class Mapper::Impl {
 public:
  Impl(const PinholeCamera& camera, const MapperOptions& options, SlamMode mode)
      : camera_(camera), options_(options), mode_(mode), adjuster_(baOptions(options, mode)),
        loop_closer_(camera, loopOptions(options, mode)) {}

  MapperResult addKeyframe(const KeyframeData& data, const std::atomic<bool>* interrupt);
  void load(const LoadedMap& loaded);
  bool refine(const std::atomic<bool>* interrupt);
  MapChanges takeChanges() { return std::exchange(changes_, MapChanges{}); }
  const Map& map() const { return map_; }
  const LoopClosureCounters& loopClosures() const { return loop_closer_.counters(); }
  const std::vector<LoopClosureResult>& loopsRecognised() const { return loop_closer_.recognised(); }
  long keyframesCulled() const { return keyframes_culled_; }
  MapParts parts() const;
  const AnchorCounts& anchors() const { return anchors_; }
  KeyframesKept keyframesKept() const { return rgbdslam::keyframesKept(map_, modeCullOptions()); }
  void removeKeyframes(const std::vector<KeyframeId>& ids);

 private:
  // Mono's scale drifts: an SE(3) pose graph cannot take that out (loop_closer.h).
  static LoopClosureOptions loopOptions(const MapperOptions& options, SlamMode mode) {
    LoopClosureOptions loop = options.loop_closure;
    loop.enabled = loop.enabled && mode != SlamMode::kMono;
    return loop;
  }
  static BaOptions baOptions(const MapperOptions& options, SlamMode mode) {
    BaOptions ba = options.ba;
    ba.use_depth = ba.use_depth && mode == SlamMode::kDepthBa;
    return ba;
  }
  std::string checkKeyframe(const KeyframeData& data) const;
  void integrate(const KeyframeData& data, MapperResult* result);
  KeyframeId partOf(const KeyframeData& data) const;
  SE3 anchorMove(const KeyframeData& data, KeyframeId part, MapperResult* result) const;
  std::optional<SE3> anchorPoseNow(KeyframeId anchor, KeyframeId part, bool* via_stand_in) const;
  void rememberStandIns(const KeyframeCullResult& culled);
  void addPoint(const MapPoint& point);
  void addMeasurement(KeyframeId kf, Measurement m);
  KeyframeId epipolarPartner(const Keyframe& kf) const;
  std::vector<KeyframeId> epipolarPartners(const Keyframe& kf) const;
  int addEpipolarPoints(const Keyframe& kf);
  int addEpipolarPointsWith(const Keyframe& kf, const Keyframe& other, int created_before);
  BaResult runBa(const std::set<KeyframeId>& free_keyframes, const std::atomic<bool>* interrupt);
  std::set<KeyframeId> localWindow(const Keyframe& kf) const;
  std::set<KeyframeId> globalWindow() const;
  bool refindNewPoints(const std::atomic<bool>* interrupt);
  void cull();
  void cullKeyframes();
  CullOptions modeCullOptions() const;  // the culling options of this mode
  void noteRemoval(const KeyframeCullResult& culled);

  PinholeCamera camera_;
  MapperOptions options_;
  SlamMode mode_;
  BundleAdjuster adjuster_;
  LoopCloser loop_closer_;
  Map map_;
  std::deque<PointId> refind_queue_;  // new points not yet searched in the other keyframes
  std::set<std::pair<PointId, KeyframeId>> pending_outliers_;  // 2-D outliers to remove
  bool global_ba_needed_ = false;
  bool cull_needed_ = false;
  bool keyframe_cull_needed_ = false;  // a keyframe came since the last keyframe culling
  std::vector<KeyframeId> added_since_keyframe_cull_;
  long keyframes_culled_ = 0;
  long parts_started_ = 0;  // keyframes that started a part (not keyframe 0's)
  AnchorCounts anchors_;
  int keyframes_since_global_ba_ = 0;
  MapChanges changes_;  // since the last takeChanges()
  // A culled keyframe's stand-in (anchorMove): the nearest keyframe of its part that stayed,
  // and the culled keyframe's pose relative to it then. The tracker anchors keyframes to
  // keyframes of its replica, which learns of a cull only with the next map update (an
  // outage delays it by its length), so a keyframe can come anchored to one culled since.
  // The newest kMaxStandIns are kept, the oldest dropped first.
  struct StandIn {
    KeyframeId by = -1;
    SE3 T_by_culled;
  };
  std::unordered_map<KeyframeId, StandIn> stand_ins_;
  std::deque<KeyframeId> stand_in_order_;  // oldest first
  bool changed_in_call_ = false;  // refine(): this call changed the map
};

std::string Mapper::Impl::checkKeyframe(const KeyframeData& data) const {
  if (map_.hasKeyframe(data.id)) return "keyframe " + std::to_string(data.id) + " is already in the map";
  if (data.grey.empty() || data.grey.type() != CV_8UC1) return "grey image missing or not CV_8UC1";
  if (data.grey.cols != camera_.width || data.grey.rows != camera_.height) return "image size differs from the camera's";
  if (!data.depth.empty() && (data.depth.type() != CV_16UC1 || data.depth.size() != data.grey.size())) {
    return "depth image not CV_16UC1 of the image's size";
  }
  return "";
}

MapperResult Mapper::Impl::addKeyframe(const KeyframeData& data, const std::atomic<bool>* interrupt) {
  MapperResult result;
  result.error = checkKeyframe(data);
  if (!result.error.empty()) {
    result.status = MapperResult::Status::kBadKeyframe;
    return result;
  }
  const auto start = Clock::now();
  integrate(data, &result);
  result.integrate_ms = msSince(start);
  const Keyframe& kf = *map_.keyframe(data.id);
  const auto ba_start = Clock::now();
  runBa(localWindow(kf), interrupt);
  result.local_ba_ms = msSince(ba_start);
  updateMedianDepth(map_, map_.keyframe(data.id));
  changes_.keyframes.insert(data.id);
  result.loop = loop_closer_.onKeyframe(&map_, data.id, &changes_);
  if (result.loop.closed) global_ba_needed_ = true;
  global_ba_needed_ = global_ba_needed_ || ++keyframes_since_global_ba_ >= options_.ba_windows.global_ba_every;
  cull_needed_ = true;
  keyframe_cull_needed_ = true;
  added_since_keyframe_cull_.push_back(data.id);
  result.status = MapperResult::Status::kIntegrated;
  return result;
}

// The saved map as it was: no bundle adjustment, no re-finding, no culling, no changes to
// publish (whoever loads the mapper's map loads the tracker's from the same file).
void Mapper::Impl::load(const LoadedMap& loaded) {
  for (size_t i = 0; i < loaded.keyframes.size(); ++i) {
    map_.addKeyframe(loaded.buildKeyframe(i, options_.keyframe_build));
  }
  for (const MapPointData& p : loaded.points) map_.addPoint(MapPoint(p));  // one part: files name none
  MapChanges none;  // places only: nothing is closed or moved
  for (const KeyframeData& kf : loaded.keyframes) loop_closer_.onKeyframe(&map_, kf.id, &none, /*close=*/false);
}

void Mapper::Impl::integrate(const KeyframeData& data, MapperResult* result) {
  const KeyframeId part = partOf(data);
  const SE3 moved = anchorMove(data, part, result);
  const SE3 T_w_c = moved * data.T_w_c;
  result->anchor_moved_m = (T_w_c.translation() - data.T_w_c.translation()).norm();
  result->anchor_moved_deg = T_w_c.rotation().angularDistance(data.T_w_c.rotation()) * 180.0 / M_PI;
  anchors_.placed += options_.move_with_anchor && data.anchor >= 0 && !data.new_part && !result->anchor_missing &&
                     !result->anchor_refused;
  anchors_.stand_in += result->anchor_stand_in;
  anchors_.missing += result->anchor_missing;
  anchors_.refused += result->anchor_refused;
  KeyframeData bare;  // the image content only; points and measurements are added checked
  bare.utime = data.utime, bare.map_id = data.map_id, bare.id = data.id, bare.T_w_c = T_w_c;
  bare.grey = data.grey, bare.depth = data.depth, bare.depth_scale = data.depth_scale;
  KeyframeBuildOptions build = options_.keyframe_build;
  if (data.grey_lossy) build.corners = lossyCornerOptions(build.corners);
  Keyframe* kf = map_.addKeyframe(makeKeyframe(bare, build));
  kf->part = part;
  if (part == kf->id && kf->id != 0) ++parts_started_;
  for (MapPointData p : data.new_points) {
    p.p_w = moved * p.p_w;
    addPoint(MapPoint(p));
  }
  for (const Measurement& m : data.measurements) {
    const MapPoint* point = map_.point(m.point_id);
    if (!point) ++result->dropped_measurements;
    else if (map_.partOfPoint(*point) != part) ++result->cross_part_measurements;
    else addMeasurement(kf->id, m);
  }
  // A provisional point whose source measurement was not sent gets it from its patch.
  for (const MapPointData& p : data.new_points) {
    if (p.source_keyframe == kf->id && !kf->measurements().count(p.id)) {
      const auto d = kf->depthAt(p.uv);
      addMeasurement(kf->id, Measurement{p.id, p.uv, p.level, d ? *d : 0.0});
    }
  }
  result->epipolar_points = addEpipolarPoints(*kf);
}

// Tracked against the map as the tracker had it: the move of its anchor since ("Anchor"), if
// the anchor is in the map (or culled with a stand-in on record), in the part the keyframe joins, and the move keeps the keyframe
// and its points within the world (a sender can name an anchor pose that passes the
// protocol's bound alone and together with the keyframe's does not); else none.
SE3 Mapper::Impl::anchorMove(const KeyframeData& data, KeyframeId part, MapperResult* result) const {
  if (!options_.move_with_anchor || data.anchor < 0 || data.new_part) return SE3();
  bool via_stand_in = false;
  const std::optional<SE3> anchor = anchorPoseNow(data.anchor, part, &via_stand_in);
  if (!anchor) {
    result->anchor_missing = true;
    return SE3();
  }
  const SE3 moved = *anchor * data.T_w_anchor.inverse();
  const auto inWorld = [](const Vec3& p) { return p.cwiseAbs().maxCoeff() <= kWorldBoundM; };
  bool within = inWorld((moved * data.T_w_c).translation());
  for (const MapPointData& p : data.new_points) within = within && inWorld(moved * p.p_w);
  if (!within) {
    result->anchor_refused = true;
    return SE3();
  }
  result->anchor_stand_in = via_stand_in;
  return moved;
}

// The anchor keyframe's pose in the map now: its own, or if it was culled, where its
// stand-in (and its stand-in's, if that was culled too) carried it. None when it is in no
// record or in another part.
std::optional<SE3> Mapper::Impl::anchorPoseNow(KeyframeId anchor, KeyframeId part, bool* via_stand_in) const {
  SE3 T_by_anchor;  // the anchor relative to the keyframe reached so far
  KeyframeId id = anchor;
  for (size_t step = 0; step <= stand_ins_.size(); ++step) {  // each record is followed once at most
    if (const Keyframe* kf = map_.keyframe(id)) {
      if (kf->part != part) return std::nullopt;
      return *via_stand_in ? kf->T_w_c * T_by_anchor : kf->T_w_c;  // (a product renormalises)
    }
    const auto it = stand_ins_.find(id);
    if (it == stand_ins_.end()) return std::nullopt;
    T_by_anchor = it->second.T_by_culled * T_by_anchor;
    id = it->second.by;
    *via_stand_in = true;
  }
  return std::nullopt;
}

// Counted in culls: a keyframe can come anchored to a keyframe culled up to this many culls
// ago. The 10-minute flight culls about 75 a minute (1056 made, 301 left in the map), so
// 2048 cover more than 25 minutes of culling behind the tracker, at about 150 bytes each.
constexpr size_t kMaxStandIns = 2048;

void Mapper::Impl::rememberStandIns(const KeyframeCullResult& culled) {
  for (size_t i = 0; i < culled.removed_keyframes.size() && i < culled.removed_poses.size(); ++i) {
    const auto& [T_w_culled, part] = culled.removed_poses[i];
    const std::vector<KeyframeId> nearest = map_.nearestKeyframesInPart(T_w_culled, 1, part);
    if (nearest.empty()) continue;
    const KeyframeId id = culled.removed_keyframes[i];
    stand_ins_[id] = StandIn{nearest.front(), map_.keyframe(nearest.front())->T_w_c.inverse() * T_w_culled};
    stand_in_order_.push_back(id);
  }
  while (stand_in_order_.size() > kMaxStandIns) {
    stand_ins_.erase(stand_in_order_.front());
    stand_in_order_.pop_front();
  }
}

// The part a keyframe joins (mapper.h, "Parts"): a new one when it says so (the tracker
// started it where it was lost), else the part whose points it measures most (ties: the
// older part), else, measuring no known point, the newest keyframe's.
KeyframeId Mapper::Impl::partOf(const KeyframeData& data) const {
  if (map_.keyframes().empty()) return data.id;
  if (data.new_part) return data.id;
  std::map<KeyframeId, int> measured;
  for (const Measurement& m : data.measurements) {
    if (const MapPoint* point = map_.point(m.point_id)) {
      const KeyframeId part = map_.partOfPoint(*point);
      if (part >= 0) ++measured[part];
    }
  }
  KeyframeId best = map_.keyframes().rbegin()->second->part;
  int best_count = 0;
  for (const auto& [part, count] : measured) {
    if (count > best_count) best = part, best_count = count;
  }
  return best;
}

void Mapper::Impl::addPoint(const MapPoint& point) {
  map_.addPoint(point);
  changes_.points.insert(point.id);
  changes_.removed_points.erase(point.id);
  refind_queue_.push_back(point.id);
}

void Mapper::Impl::addMeasurement(KeyframeId kf, Measurement m) {
  if (!depthPointsAllowed(mode_, kf)) m.depth = 0.0;  // mono: depth of keyframe 0 only
  map_.addMeasurement(kf, m);
}

// The partner for epipolar search: the nearest keyframe, unless keyframes are dense (the
// camera moving forward into a view with few points takes one every few frames); then the
// one farthest away within epipolar_partner_distance_ratio * median depth whose optical axis
// is within epipolar_partner_max_angle_deg, so that points have parallax to triangulate.
KeyframeId Mapper::Impl::epipolarPartner(const Keyframe& kf) const {
  KeyframeId nearest = -1;
  for (KeyframeId id : map_.nearestKeyframesInPart(kf.T_w_c, 2, kf.part)) {
    if (id != kf.id) {
      nearest = id;
      break;
    }
  }
  if (nearest < 0 || options_.epipolar_partners.distance_ratio <= 0.0) return nearest;
  const double max_distance = options_.epipolar_partners.distance_ratio * kf.median_depth;
  const double min_cos = std::cos(options_.epipolar_partners.max_angle_deg * M_PI / 180.0);
  const Vec3 axis = kf.T_w_c.rotationMatrix().col(2);
  KeyframeId best = nearest;
  double best_distance =
      (map_.keyframe(nearest)->T_w_c.translation() - kf.T_w_c.translation()).norm();
  for (const auto& [id, other] : map_.keyframes()) {
    if (id == kf.id || other->part != kf.part) continue;
    const double distance = (other->T_w_c.translation() - kf.T_w_c.translation()).norm();
    if (distance <= best_distance || distance > max_distance) continue;
    if (axis.dot(other->T_w_c.rotationMatrix().col(2)) < min_cos) continue;
    best = id;
    best_distance = distance;
  }
  return best;
}

// The partner above; in mono (every point from epipolar search) also the other keyframes
// within epipolar_partner_max_angle_deg, nearest first, up to epipolar_partners_mono.
std::vector<KeyframeId> Mapper::Impl::epipolarPartners(const Keyframe& kf) const {
  std::vector<KeyframeId> partners;
  const KeyframeId first = epipolarPartner(kf);
  if (first < 0) return partners;
  partners.push_back(first);
  if (depthPointsAllowed(mode_, kf.id)) return partners;
  const double min_cos = std::cos(options_.epipolar_partners.max_angle_deg * M_PI / 180.0);
  const Vec3 axis = kf.T_w_c.rotationMatrix().col(2);
  const size_t wanted = static_cast<size_t>(options_.epipolar_partners.partners_mono);
  for (KeyframeId id : map_.nearestKeyframesInPart(kf.T_w_c, map_.numKeyframes(), kf.part)) {
    if (partners.size() >= wanted) break;
    if (id == kf.id || id == first) continue;
    if (axis.dot(map_.keyframe(id)->T_w_c.rotationMatrix().col(2)) < min_cos) continue;
    partners.push_back(id);
  }
  return partners;
}

int Mapper::Impl::addEpipolarPoints(const Keyframe& kf) {
  if (options_.epipolar.max_points <= 0) return 0;
  int created = 0;
  for (KeyframeId other_id : epipolarPartners(kf)) {
    created += addEpipolarPointsWith(kf, *map_.keyframe(other_id), created);
  }
  return created;
}

// Points of 'kf' triangulated against 'other'; ids continue after 'created_before'.
int Mapper::Impl::addEpipolarPointsWith(const Keyframe& kf, const Keyframe& other,
                                        int created_before) {
  EpipolarOptions eo = options_.epipolar;
  // Weak corners only where every point must come from epipolar search (mono): in the depth
  // modes the keyframe's points from depth already took the weak corners that have depth.
  if (depthPointsAllowed(mode_, kf.id)) eo.weak_until_points = 0;
  eo.skip_corners_with_depth = depthPointsAllowed(mode_, kf.id);
  eo.cross_check = eo.cross_check && depthPointsAllowed(mode_, kf.id);  // see EpipolarOptions
  const PointId first_id = mapperPointId(kf.id, created_before);
  const auto created = epipolarSearch(kf, other, camera_, eo, options_.matching, first_id);
  for (const EpipolarPoint& ep : created) {
    addPoint(ep.point);
    Measurement in_kf = ep.in_keyframe, in_other = ep.in_other;
    if (const auto d = kf.depthAt(in_kf.uv)) in_kf.depth = *d;
    if (const auto d = other.depthAt(in_other.uv)) in_other.depth = *d;
    addMeasurement(kf.id, in_kf);
    addMeasurement(other.id, in_other);
  }
  return static_cast<int>(created.size());
}

std::set<KeyframeId> Mapper::Impl::localWindow(const Keyframe& kf) const {
  std::set<KeyframeId> window{kf.id};
  const int neighbours = options_.ba_windows.local_ba_neighbours;
  for (KeyframeId id : map_.nearestKeyframesInPart(kf.T_w_c, neighbours + 1, kf.part)) {
    if (window.size() > static_cast<size_t>(neighbours)) break;
    window.insert(id);
  }
  window.erase(0);
  return window;
}

std::set<KeyframeId> Mapper::Impl::globalWindow() const {
  std::set<KeyframeId> window;
  for (const auto& [id, kf] : map_.keyframes()) {
    if (id != 0) window.insert(id);
  }
  while (static_cast<int>(window.size()) > options_.ba_windows.max_global_ba_keyframes) {
    window.erase(window.begin());
  }
  return window;
}

BaResult Mapper::Impl::runBa(const std::set<KeyframeId>& free_keyframes, const std::atomic<bool>* interrupt) {
  // 2-D BA leaves the scale free: keyframe 0's points (the map initialisation from measured
  // depth) stay fixed and hold it. With depth residuals every depth reading holds it.
  const bool fix_initial_points = mode_ != SlamMode::kDepthBa;
  MapBaProblem ba = buildBaProblem(map_, camera_, free_keyframes, /*min_fixed_keyframes=*/1,
                                   fix_initial_points);
  BaResult result = adjuster_.solve(&ba.problem, interrupt);
  if (!usableResult(result)) return result;
  std::set<PointId> moved;
  if (writeBackBa(ba, &map_, &changes_.keyframes, &moved) > 0) changed_in_call_ = true;
  applyBaOutliers(ba, result, &map_, &pending_outliers_);
  // Points carried off go at once, before any publication can hold them (map_maintenance.h).
  for (PointId pid : cullDivergedPoints(&map_, std::vector<PointId>(moved.begin(), moved.end()),
                                        options_.cull.max_depth_m)) {
    moved.erase(pid);
    changes_.points.erase(pid);
    changes_.removed_points.insert(pid);
  }
  changes_.points.insert(moved.begin(), moved.end());
  cull_needed_ = true;
  return result;
}

bool Mapper::Impl::refindNewPoints(const std::atomic<bool>* interrupt) {
  bool added = false;
  while (!refind_queue_.empty() && !interrupted(interrupt)) {
    const PointId pid = refind_queue_.front();
    refind_queue_.pop_front();
    const MapPoint* point = map_.point(pid);
    const Keyframe* source = point ? map_.keyframe(point->source_keyframe) : nullptr;
    if (!source) continue;
    for (const auto& [kf_id, kf] : map_.keyframes()) {
      if (kf->part != source->part || kf->measurements().count(pid)) continue;
      auto m = findPointInKeyframe(*point, *source, *kf, camera_, options_.refind, options_.matching);
      if (!m) continue;
      if (const auto d = kf->depthAt(m->uv)) m->depth = *d;
      addMeasurement(kf_id, *m);
      added = true;
    }
  }
  return added;
}

void Mapper::Impl::cull() {
  const CullResult culled = cullMap(&map_, &pending_outliers_, options_.cull);
  for (PointId pid : culled.removed_points) {
    changes_.removed_points.insert(pid);
    changes_.points.erase(pid);
    changed_in_call_ = true;
  }
  if (!culled.removed_points.empty() || culled.removed_measurements > 0) global_ba_needed_ = true;
  cull_needed_ = false;
}

// Redundant keyframes (map_maintenance.h) among those that share a point with a keyframe
// integrated since the last call (its covisible keyframes, as ORB-SLAM's local keyframes),
// but for the newest keyframe_cull_min_age: once per new keyframe, after its points were
// re-found in the others and outliers culled (the rule counts measurements). Why covisible,
// not the newest ones: a keyframe becomes redundant as later keyframes measure its points,
// which on the corridor goes on for metres (a point is measured in 21.6 keyframes on average).
void Mapper::Impl::cullKeyframes() {
  keyframe_cull_needed_ = false;
  const std::vector<KeyframeId> added = std::exchange(added_since_keyframe_cull_, {});
  if (!options_.cull.cull_keyframes || map_.keyframes().empty()) return;
  const int min_age = options_.cull.keyframe_cull_min_age;
  std::set<KeyframeId> young;
  for (auto it = map_.keyframes().rbegin(); it != map_.keyframes().rend() && static_cast<int>(young.size()) < min_age; ++it) {
    young.insert(it->first);
  }
  std::set<KeyframeId> covisible;
  for (KeyframeId id : added) {
    const Keyframe* kf = map_.keyframe(id);
    if (!kf) continue;
    for (const auto& [pid, m] : kf->measurements()) {
      for (KeyframeId other : map_.observers(pid)) {
        if (other != 0 && !young.count(other)) covisible.insert(other);
      }
    }
  }
  const std::vector<KeyframeId> candidates(covisible.begin(), covisible.end());
  noteRemoval(cullRedundantKeyframes(&map_, candidates, modeCullOptions(), &pending_outliers_));
}

CullOptions Mapper::Impl::modeCullOptions() const {
  CullOptions cull = options_.cull;
  if (mode_ == SlamMode::kDepthBa) cull.keyframe_redundant_observers = cull.keyframe_redundant_observers_depth;
  return cull;
}

void Mapper::Impl::removeKeyframes(const std::vector<KeyframeId>& ids) {
  noteRemoval(rgbdslam::removeKeyframes(&map_, ids, &pending_outliers_));
}

void Mapper::Impl::noteRemoval(const KeyframeCullResult& culled) {
  if (culled.removed_keyframes.empty()) return;
  rememberStandIns(culled);
  for (KeyframeId id : culled.removed_keyframes) {
    changes_.keyframes.erase(id);
    changes_.removed_keyframes.insert(id);
    loop_closer_.onKeyframeRemoved(id);
  }
  changes_.points.insert(culled.resourced_points.begin(), culled.resourced_points.end());
  for (PointId pid : culled.removed_points) {
    changes_.points.erase(pid);
    changes_.removed_points.insert(pid);
  }
  keyframes_culled_ += static_cast<long>(culled.removed_keyframes.size());
  changed_in_call_ = true;
  global_ba_needed_ = true;
}

bool Mapper::Impl::refine(const std::atomic<bool>* interrupt) {
  if (map_.numKeyframes() == 0) return false;
  changed_in_call_ = false;
  if (!refind_queue_.empty() && refindNewPoints(interrupt)) global_ba_needed_ = true;
  if (global_ba_needed_ && !interrupted(interrupt)) {
    const BaResult r = runBa(globalWindow(), interrupt);
    keyframes_since_global_ba_ = 0;
    // Converged, or nothing to optimise / a failure that repeating would not cure.
    if (r.status != BaResult::Status::kMaxIterations && r.status != BaResult::Status::kInterrupted) {
      global_ba_needed_ = false;
    }
  }
  if (cull_needed_ && !interrupted(interrupt)) cull();
  if (keyframe_cull_needed_ && !cull_needed_ && !interrupted(interrupt)) cullKeyframes();
  return changed_in_call_;
}

MapParts Mapper::Impl::parts() const {
  MapParts parts;
  parts.started = parts_started_;
  parts.joined = loop_closer_.counters().parts_joined;
  std::set<KeyframeId> names;
  for (const auto& [id, kf] : map_.keyframes()) names.insert(kf->part);
  parts.now = static_cast<int>(names.size());
  return parts;
}

Mapper::Mapper(const PinholeCamera& camera, const MapperOptions& options, SlamMode mode)
    : impl_(std::make_unique<Impl>(camera, options, mode)) {}
Mapper::~Mapper() = default;
MapperResult Mapper::addKeyframe(const KeyframeData& keyframe, const std::atomic<bool>* interrupt) {
  return impl_->addKeyframe(keyframe, interrupt);
}
void Mapper::load(const LoadedMap& loaded) { impl_->load(loaded); }
bool Mapper::refine(const std::atomic<bool>* interrupt) { return impl_->refine(interrupt); }
MapChanges Mapper::takeChanges() { return impl_->takeChanges(); }
const Map& Mapper::map() const { return impl_->map(); }
const LoopClosureCounters& Mapper::loopClosures() const { return impl_->loopClosures(); }
const std::vector<LoopClosureResult>& Mapper::loopsRecognised() const { return impl_->loopsRecognised(); }
long Mapper::keyframesCulled() const { return impl_->keyframesCulled(); }
MapParts Mapper::parts() const { return impl_->parts(); }
const AnchorCounts& Mapper::anchors() const { return impl_->anchors(); }
KeyframesKept Mapper::keyframesKept() const { return impl_->keyframesKept(); }
void Mapper::removeKeyframes(const std::vector<KeyframeId>& ids) { impl_->removeKeyframes(ids); }

}  // namespace rgbdslam
