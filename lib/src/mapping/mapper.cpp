// The mapper's flow (mapper.h): in-order integration, epipolar points, local and global
// bundle adjustment, re-finding of new points and culling. The building blocks live in
// epipolar_search.cpp, data_association.cpp, ba_problem.cpp and map_maintenance.cpp.
#include "rgbdslam/mapping/mapper.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <set>

#include "rgbdslam/mapping/ba_problem.h"
#include "rgbdslam/mapping/data_association.h"
#include "rgbdslam/mapping/epipolar_search.h"
#include "rgbdslam/image/patch.h"
#include "rgbdslam/mapping/map_maintenance.h"

namespace rgbdslam {

void MapperOptions::bind(OptionRegistry* r) {
  const std::string m = "mapper";
  r->bind(m, "local_ba_neighbours", &local_ba_neighbours, 0, 100, "keyframes", "nearest keyframes optimised with a new one in local BA");
  r->bind(m, "global_ba_every", &global_ba_every, 1, 1000, "keyframes", "run global BA after this many new keyframes");
  r->bind(m, "max_global_ba_keyframes", &max_global_ba_keyframes, 2, 100000, "keyframes", "above this, global BA optimises only the newest ones");
  r->bind(m, "epipolar_min_depth_m", &epipolar_min_depth_m, 0.01, 100.0, "m", "epipolar search: nearest depth along the ray");
  r->bind(m, "epipolar_max_depth_m", &epipolar_max_depth_m, 0.1, 1000.0, "m", "epipolar search: farthest depth along the ray");
  r->bind(m, "epipolar_partner_distance_ratio", &epipolar_partner_distance_ratio, 0.0, 10.0, "-", "epipolar partner: the farthest keyframe within this times the median depth (0: the nearest)");
  r->bind(m, "epipolar_partner_max_angle_deg", &epipolar_partner_max_angle_deg, 0.0, 180.0, "deg", "...whose optical axis is within this angle of the new keyframe's");
  r->bind(m, "epipolar_max_points", &epipolar_max_points, 0, 10000, "corners", "corners without depth tried per new keyframe");
  r->bind(m, "epipolar_partners_mono", &epipolar_partners_mono, 1, 100, "keyframes", "mono keyframes search against this many partners (the chosen one, then the nearest others within the angle)");
  r->bind(m, "epipolar_min_shi_tomasi", &epipolar_min_shi_tomasi, 0.0, 1e6, "(grey/px)^2", "weaker corners are not tried");
  r->bind(m, "epipolar_weak_min_shi_tomasi", &epipolar_weak_min_shi_tomasi, 0.0, 1e6, "(grey/px)^2", "a mono keyframe (no points from depth) with few points also tries corners down to this score...");
  r->bind(m, "epipolar_weak_until_points", &epipolar_weak_until_points, 0, 100000, "points", "...until it measures this many points (0: never)");
  r->bind(m, "epipolar_min_separation_px", &epipolar_min_separation_px, 0.0, 100.0, "px", "distance from points the keyframe measures (level 0)");
  r->bind(m, "epipolar_line_tolerance_px", &epipolar_line_tolerance_px, 0.1, 20.0, "level px", "corner distance from the epipolar segment");
  r->bind(m, "epipolar_distinctiveness", &epipolar_distinctiveness, 0.0, 1.0, "-", "best ZMSSD must be below this times the second best");
  r->bind(m, "epipolar_min_parallax_deg", &epipolar_min_parallax_deg, 0.0, 90.0, "deg", "smaller ray angles do not triangulate");
  r->bind(m, "epipolar_max_reprojection_px", &epipolar_max_reprojection_px, 0.1, 20.0, "level px", "triangulated point's error in either view");
  r->bind(m, "max_zmssd_per_pixel", &max_zmssd_per_pixel, 1, 65025, "grey^2", "patch acceptance (ZMSSD / 64) for epipolar search and re-finding");
  r->bind(m, "max_zmssd_flat_ratio", &max_zmssd_flat_ratio, 0.0, 2.0, "-", "...and below this times the template's zero-mean energy, which a textureless patch exceeds (0: off)");
  r->bind(m, "refind_search_radius_px", &refind_search_radius_px, 1, 50, "level px", "re-finding: search radius around the prediction");
  r->bind(m, "min_good_measurements", &min_good_measurements, 1, 100, "measurements", "points with fewer good measurements are culled");
  r->bind(m, "keep_source_only_keyframes", &keep_source_only_keyframes, 0, 1000, "keyframes", "source-only points survive while their keyframe is this recent");
  r->bind(m, "max_outlier_fraction", &max_outlier_fraction, 0.0, 1.0, "-", "points with a larger share of outlier measurements are culled");
  r->bind(m, "min_depth_m", &keyframe_build.min_depth_m, 0.0, 100.0, "m", "keyframe depth readings nearer than this are invalid");
  r->bind(m, "max_depth_m", &keyframe_build.max_depth_m, 0.1, 100.0, "m", "keyframe depth readings farther than this are invalid");
  const std::string b = "bundle_adjustment";
  r->bind(b, "sigma_2d_k", &ba.sigma_2d_k, 1e-3, 100.0, "px", "2-D noise: sigma = k * 2^level");
  r->bind(b, "depth_sigma_a", &ba.depth_sigma_a, 1e-6, 1.0, "1/m", "depth noise: sigma = a * d^2");
  r->bind(b, "tukey_c", &ba.tukey_c, 0.1, 100.0, "sigma_T", "Tukey biweight cut-off");
  r->bind(b, "min_sigma_t", &ba.min_sigma_t, 1e-3, 100.0, "sigma", "floor of the robust scale sigma_T");
  r->bind(b, "max_iterations", &ba.max_iterations, 1, 1000, "iterations", "Levenberg-Marquardt iterations per solve");
  r->bind(b, "robust_rounds", &ba.robust_rounds, 1, 20, "rounds", "IRLS passes (estimate sigma_T, solve)");
  r->bind(b, "function_tolerance", &ba.function_tolerance, 0.0, 1.0, "-", "stop when |cost change| / cost is below");
  r->bind(b, "gradient_tolerance", &ba.gradient_tolerance, 0.0, 1.0, "-", "stop when max |gradient| is below");
  r->bind(b, "parameter_tolerance", &ba.parameter_tolerance, 0.0, 1.0, "-", "stop when |step| / |x| is below");
  r->bind(b, "num_threads", &ba.num_threads, 1, 64, "threads", "Ceres threads");
  r->bind(b, "dense_schur_max_poses", &ba.dense_schur_max_poses, 1, 10000, "poses", "automatic solver: dense Schur up to this many free poses");
  for (auto [low, high] : {std::pair{"min_depth_m", "max_depth_m"}, {"epipolar_min_depth_m", "epipolar_max_depth_m"}}) r->requireBelow(m, low, high);
}

const char* toString(MapperResult::Status status) {
  switch (status) {
    case MapperResult::Status::kIntegrated: return "integrated";
    case MapperResult::Status::kDuplicate: return "duplicate";
    case MapperResult::Status::kOutOfOrder: return "out_of_order";
    case MapperResult::Status::kForeignMap: return "foreign_map";
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
  for (const auto& [pid, m] : kf->measurements) {
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
      : camera_(camera), options_(options), mode_(mode), adjuster_(baOptions(options, mode)) {}

  MapperResult addKeyframe(const KeyframeData& data, const std::atomic<bool>* interrupt);
  std::optional<MapUpdate> refine(const std::atomic<bool>* interrupt);
  MapUpdate snapshot() const;
  const Map& map() const { return map_; }
  int64_t version() const { return version_; }

 private:
  static BaOptions baOptions(const MapperOptions& options, SlamMode mode) {
    BaOptions ba = options.ba;
    ba.use_depth = mode == SlamMode::kDepthBa;
    return ba;
  }
  std::string checkKeyframe(const KeyframeData& data) const;
  void integrate(const KeyframeData& data, MapperResult* result);
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
  std::set<KeyframeId> recentKeyframes() const;
  std::vector<KeyframeId> ackList() const;
  MapUpdate acknowledgement() const;
  MapUpdate takeDelta();
  bool hasChanges() const {
    return !changed_keyframes_.empty() || !changed_points_.empty() || !removed_points_.empty();
  }

  PinholeCamera camera_;
  MapperOptions options_;
  SlamMode mode_;
  BundleAdjuster adjuster_;
  Map map_;
  std::optional<int64_t> map_id_;
  KeyframeId next_id_ = 0;
  int64_t version_ = 0;
  int64_t utime_ = 0;
  std::deque<PointId> refind_queue_;  // new points not yet searched in the other keyframes
  std::set<std::pair<PointId, KeyframeId>> pending_outliers_;  // 2-D outliers to remove
  bool global_ba_needed_ = false;
  bool cull_needed_ = false;
  int keyframes_since_global_ba_ = 0;
  std::set<KeyframeId> changed_keyframes_;  // since the last published delta
  std::set<PointId> changed_points_, removed_points_;
};

std::string Mapper::Impl::checkKeyframe(const KeyframeData& data) const {
  if (data.grey.empty() || data.grey.type() != CV_8UC1) return "grey image missing or not CV_8UC1";
  if (data.grey.cols != camera_.width || data.grey.rows != camera_.height) return "image size differs from the camera's";
  if (!data.depth.empty() && (data.depth.type() != CV_16UC1 || data.depth.size() != data.grey.size())) {
    return "depth image not CV_16UC1 of the image's size";
  }
  return "";
}

MapperResult Mapper::Impl::addKeyframe(const KeyframeData& data, const std::atomic<bool>* interrupt) {
  MapperResult result;
  if (map_id_ && data.map_id != *map_id_) {
    result.status = MapperResult::Status::kForeignMap;
    result.error = "keyframe of map " + std::to_string(data.map_id) + ", the mapper holds map " +
                   std::to_string(*map_id_);
    return result;
  }
  if (data.id < next_id_ || data.id > next_id_) {
    result.status = data.id < next_id_ ? MapperResult::Status::kDuplicate : MapperResult::Status::kOutOfOrder;
    result.update = acknowledgement();
    return result;
  }
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
  changed_keyframes_.insert(data.id);
  global_ba_needed_ = global_ba_needed_ || ++keyframes_since_global_ba_ >= options_.global_ba_every;
  cull_needed_ = true;
  result.status = MapperResult::Status::kIntegrated;
  result.update = takeDelta();
  return result;
}

void Mapper::Impl::integrate(const KeyframeData& data, MapperResult* result) {
  KeyframeData bare;  // the image content only; points and measurements are added checked
  bare.utime = data.utime, bare.map_id = data.map_id, bare.id = data.id, bare.T_w_c = data.T_w_c;
  bare.grey = data.grey, bare.depth = data.depth, bare.depth_scale = data.depth_scale;
  Keyframe* kf = map_.addKeyframe(makeKeyframe(bare, options_.keyframe_build));
  map_id_ = data.map_id;
  next_id_ = data.id + 1;
  utime_ = data.utime;
  for (const MapPointData& p : data.new_points) {
    MapPoint point;
    point.id = p.id, point.p_w = p.p_w, point.source_keyframe = p.source_keyframe;
    point.source_level = p.level, point.source_uv = p.uv;
    addPoint(point);
  }
  for (const Measurement& m : data.measurements) {
    if (map_.point(m.point_id)) addMeasurement(kf->id, m);
    else ++result->dropped_measurements;
  }
  // A provisional point whose source measurement was not sent gets it from its patch.
  for (const MapPointData& p : data.new_points) {
    if (p.source_keyframe == kf->id && !kf->measurements.count(p.id)) {
      const auto d = kf->depthAt(p.uv);
      addMeasurement(kf->id, Measurement{p.id, p.uv, p.level, d ? *d : 0.0});
    }
  }
  result->epipolar_points = addEpipolarPoints(*kf);
}

void Mapper::Impl::addPoint(const MapPoint& point) {
  map_.addPoint(point);
  changed_points_.insert(point.id);
  removed_points_.erase(point.id);
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
  for (KeyframeId id : map_.nearestKeyframes(kf.T_w_c, 2)) {
    if (id != kf.id) {
      nearest = id;
      break;
    }
  }
  if (nearest < 0 || options_.epipolar_partner_distance_ratio <= 0.0) return nearest;
  const double max_distance = options_.epipolar_partner_distance_ratio * kf.median_depth;
  const double min_cos = std::cos(options_.epipolar_partner_max_angle_deg * M_PI / 180.0);
  const Vec3 axis = kf.T_w_c.rotationMatrix().col(2);
  KeyframeId best = nearest;
  double best_distance =
      (map_.keyframe(nearest)->T_w_c.translation() - kf.T_w_c.translation()).norm();
  for (const auto& [id, other] : map_.keyframes()) {
    if (id == kf.id) continue;
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
  const double min_cos = std::cos(options_.epipolar_partner_max_angle_deg * M_PI / 180.0);
  const Vec3 axis = kf.T_w_c.rotationMatrix().col(2);
  const size_t wanted = static_cast<size_t>(options_.epipolar_partners_mono);
  for (KeyframeId id : map_.nearestKeyframes(kf.T_w_c, map_.numKeyframes())) {
    if (partners.size() >= wanted) break;
    if (id == kf.id || id == first) continue;
    if (axis.dot(map_.keyframe(id)->T_w_c.rotationMatrix().col(2)) < min_cos) continue;
    partners.push_back(id);
  }
  return partners;
}

int Mapper::Impl::addEpipolarPoints(const Keyframe& kf) {
  if (options_.epipolar_max_points <= 0) return 0;
  int created = 0;
  for (KeyframeId other_id : epipolarPartners(kf)) {
    created += addEpipolarPointsWith(kf, *map_.keyframe(other_id), created);
  }
  return created;
}

// Points of 'kf' triangulated against 'other'; ids continue after 'created_before'.
int Mapper::Impl::addEpipolarPointsWith(const Keyframe& kf, const Keyframe& other,
                                        int created_before) {
  EpipolarOptions eo;
  eo.min_depth_m = options_.epipolar_min_depth_m, eo.max_depth_m = options_.epipolar_max_depth_m;
  eo.max_points = options_.epipolar_max_points, eo.min_shi_tomasi = options_.epipolar_min_shi_tomasi;
  eo.weak_min_shi_tomasi = options_.epipolar_weak_min_shi_tomasi;
  // Weak corners only where every point must come from epipolar search (mono): in the depth
  // modes the keyframe's points from depth already took the weak corners that have depth.
  eo.weak_until_points = depthPointsAllowed(mode_, kf.id) ? 0 : options_.epipolar_weak_until_points;
  eo.min_separation_px = options_.epipolar_min_separation_px;
  eo.line_tolerance_px = options_.epipolar_line_tolerance_px;
  eo.distinctiveness = options_.epipolar_distinctiveness;
  eo.max_zmssd = options_.max_zmssd_per_pixel * kPatchArea;
  eo.max_zmssd_flat_ratio = options_.max_zmssd_flat_ratio;
  eo.min_parallax_deg = options_.epipolar_min_parallax_deg;
  eo.max_reprojection_px = options_.epipolar_max_reprojection_px;
  eo.skip_corners_with_depth = depthPointsAllowed(mode_, kf.id);
  const PointId first_id = kf.id * kPointsPerKeyframe + kPointsPerKeyframe / 2 + created_before;
  const auto created = epipolarSearch(kf, other, camera_, eo, first_id);
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
  for (KeyframeId id : map_.nearestKeyframes(kf.T_w_c, options_.local_ba_neighbours + 1)) {
    if (window.size() > static_cast<size_t>(options_.local_ba_neighbours)) break;
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
  while (static_cast<int>(window.size()) > options_.max_global_ba_keyframes) window.erase(window.begin());
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
  writeBackBa(ba, &map_, &changed_keyframes_, &changed_points_);
  applyBaOutliers(ba, result, &map_, &pending_outliers_);
  cull_needed_ = true;
  return result;
}

bool Mapper::Impl::refindNewPoints(const std::atomic<bool>* interrupt) {
  RefindOptions ro;
  ro.search_radius_px = options_.refind_search_radius_px;
  ro.max_zmssd = options_.max_zmssd_per_pixel * kPatchArea;
  ro.max_zmssd_flat_ratio = options_.max_zmssd_flat_ratio;
  bool added = false;
  while (!refind_queue_.empty() && !interrupted(interrupt)) {
    const PointId pid = refind_queue_.front();
    refind_queue_.pop_front();
    const MapPoint* point = map_.point(pid);
    const Keyframe* source = point ? map_.keyframe(point->source_keyframe) : nullptr;
    if (!source) continue;
    for (const auto& [kf_id, kf] : map_.keyframes()) {
      if (kf->measurements.count(pid)) continue;
      auto m = findPointInKeyframe(*point, *source, *kf, camera_, ro);
      if (!m) continue;
      if (const auto d = kf->depthAt(m->uv)) m->depth = *d;
      addMeasurement(kf_id, *m);
      added = true;
    }
  }
  return added;
}

std::set<KeyframeId> Mapper::Impl::recentKeyframes() const {
  std::set<KeyframeId> recent;
  for (auto it = map_.keyframes().rbegin(); it != map_.keyframes().rend(); ++it) {
    if (static_cast<int>(recent.size()) >= options_.keep_source_only_keyframes) break;
    recent.insert(it->first);
  }
  return recent;
}

void Mapper::Impl::cull() {
  const CullOptions co{options_.min_good_measurements, options_.max_outlier_fraction};
  const CullResult culled = cullMap(&map_, &pending_outliers_, recentKeyframes(), co);
  for (PointId pid : culled.removed_points) {
    removed_points_.insert(pid);
    changed_points_.erase(pid);
  }
  if (!culled.removed_points.empty() || culled.removed_measurements > 0) global_ba_needed_ = true;
  cull_needed_ = false;
}

std::optional<MapUpdate> Mapper::Impl::refine(const std::atomic<bool>* interrupt) {
  if (map_.numKeyframes() == 0) return std::nullopt;
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
  if (!hasChanges()) return std::nullopt;
  return takeDelta();
}

std::vector<KeyframeId> Mapper::Impl::ackList() const {
  std::vector<KeyframeId> ids;
  for (const auto& [id, kf] : map_.keyframes()) ids.push_back(id);
  return ids;
}

MapUpdate Mapper::Impl::acknowledgement() const {
  MapUpdate u;
  u.utime = utime_;
  u.map_id = map_id_.value_or(0);
  u.version = version_;
  u.acked_keyframes = ackList();
  return u;
}

MapUpdate Mapper::Impl::takeDelta() {
  MapUpdate u = acknowledgement();
  u.version = ++version_;
  for (KeyframeId id : changed_keyframes_) {
    if (const Keyframe* kf = map_.keyframe(id)) u.keyframes.push_back({id, kf->T_w_c});
  }
  for (PointId id : changed_points_) {
    if (const MapPoint* p = map_.point(id)) u.points.push_back(p->data());
  }
  u.removed_points.assign(removed_points_.begin(), removed_points_.end());
  changed_keyframes_.clear();
  changed_points_.clear();
  removed_points_.clear();
  return u;
}

MapUpdate Mapper::Impl::snapshot() const {
  MapUpdate u = acknowledgement();
  u.is_snapshot = true;
  for (const auto& [id, kf] : map_.keyframes()) u.keyframes.push_back({id, kf->T_w_c});
  for (PointId id : sortedPointIds(map_)) u.points.push_back(map_.point(id)->data());
  return u;
}

Mapper::Mapper(const PinholeCamera& camera, const MapperOptions& options, SlamMode mode)
    : impl_(std::make_unique<Impl>(camera, options, mode)) {}
Mapper::~Mapper() = default;
MapperResult Mapper::addKeyframe(const KeyframeData& keyframe, const std::atomic<bool>* interrupt) {
  return impl_->addKeyframe(keyframe, interrupt);
}
std::optional<MapUpdate> Mapper::refine(const std::atomic<bool>* interrupt) { return impl_->refine(interrupt); }
MapUpdate Mapper::snapshot() const { return impl_->snapshot(); }
const Map& Mapper::map() const { return impl_->map(); }
int64_t Mapper::version() const { return impl_->version(); }

}  // namespace rgbdslam
