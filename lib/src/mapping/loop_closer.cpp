#include "rgbdslam/mapping/loop_closer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <map>
#include <set>

namespace rgbdslam {
namespace {

using LoopClock = std::chrono::steady_clock;

double loopMsSince(LoopClock::time_point start) {
  return std::chrono::duration<double, std::milli>(LoopClock::now() - start).count();
}

constexpr double kLoopDegPerRad = 180.0 / M_PI;

double loopAngleDeg(const SE3& T) { return T.log().tail<3>().norm() * kLoopDegPerRad; }

// The keyframes that measure a point that 'kf' measures: tied to it by bundle adjustment already.
std::vector<KeyframeId> keyframesSharingPoints(const Map& map, const Keyframe& kf) {
  std::set<KeyframeId> sharing;
  for (const auto& [pid, m] : kf.measurements()) {
    for (KeyframeId other : map.observers(pid)) sharing.insert(other);
  }
  sharing.erase(kf.id);
  return {sharing.begin(), sharing.end()};
}

// The gauge: the oldest keyframe of each connected part of the graph is fixed (of a map of one
// part, keyframe 0; a part no loop edge joins to the others stays where it is).
void fixOldestOfEachComponent(PoseGraph* graph) {
  std::map<KeyframeId, KeyframeId> parent;
  for (const PoseGraphNode& node : graph->nodes) parent[node.id] = node.id;
  const auto root = [&parent](KeyframeId id) {
    while (parent[id] != id) id = parent[id] = parent[parent[id]];
    return id;
  };
  for (const PoseGraphEdge& e : graph->edges) {
    if (!parent.count(e.from) || !parent.count(e.to)) continue;
    const KeyframeId a = root(e.from), b = root(e.to);
    parent[std::max(a, b)] = std::min(a, b);
  }
  for (PoseGraphNode& node : graph->nodes) node.fixed = root(node.id) == node.id;
}

}  // namespace

void LoopClosureOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "enabled", &enabled, "close loops in the mapper (depth modes; never in mono)");
  r->bind(s, "min_keyframe_gap", &min_keyframe_gap, 1, 1000000, "keyframes",
          "a loop candidate is at least this many keyframes older than the new one");
  r->bind(s, "odometry_sigma_min_m", &odometry_sigma_min_m, 1e-6, 10.0, "m",
          "1-sigma drift between consecutive keyframes in the pose graph, at least...");
  r->bind(s, "odometry_sigma_fraction", &odometry_sigma_fraction, 0.0, 10.0, "",
          "...or this fraction of their distance");
  r->bind(s, "odometry_sigma_min_deg", &odometry_sigma_min_deg, 1e-6, 180.0, "deg",
          "1-sigma rotation drift between consecutive keyframes, at least...");
  r->bind(s, "odometry_sigma_deg_per_m", &odometry_sigma_deg_per_m, 0.0, 180.0, "deg/m",
          "...or this much per metre between them");
  r->bind(s, "loop_sigma_min_m", &loop_sigma_min_m, 1e-6, 10.0, "m", "a loop edge's 1-sigma translation, at least");
  r->bind(s, "loop_sigma_min_deg", &loop_sigma_min_deg, 1e-6, 180.0, "deg", "...and rotation");
  r->bind(s, "min_correction_m", &min_correction_m, 0.0, 100.0, "m",
          "a closure that moves no keyframe further than this...");
  r->bind(s, "min_correction_deg", &min_correction_deg, 0.0, 180.0, "deg", "...nor turns one further changes nothing");
  r->bind(s, "agree_sigmas", &agree_sigmas, 0.0, 1000.0, "sigmas",
          "a recognised place whose loop edge the map already meets within this many of its sigmas "
          "closes nothing (0: every one is solved)");
  r->bind(s, "join_max_speed_m_s", &join_max_speed_m_s, 0.0, 100.0, "m/s",
          "a part joins another only where its first keyframe lies within this speed times the time "
          "since that part's last keyframe before it (0: anywhere)...");
  r->bind(s, "join_margin_m", &join_margin_m, 0.0, 1000.0, "m", "...plus this");
  r->bind(s, "features", &features, 10, 10000, "features", "ORB features per keyframe for place recognition, at most");
  place.bind(r, "place_recognition");
  graph.bind(r, "pose_graph");
}

LoopCloser::LoopCloser(const PinholeCamera& camera, const LoopClosureOptions& options)
    : camera_(camera), options_(options) {}

LoopCloser::~LoopCloser() = default;

LoopClosureResult LoopCloser::onKeyframe(Map* map, KeyframeId id, MapChanges* changes, bool close) {
  LoopClosureResult result;
  const Keyframe* kf = map->keyframe(id);
  if (!close) loaded_.insert(id);
  if (!options_.enabled || !kf || kf->cold() || kf->depth.empty()) return result;
  const auto start = LoopClock::now();
  FeatureRelocaliserOptions extract;
  extract.features = options_.features;
  Features3d features = extractFeatures3d(kf->grey(), kf->depth.metres(), camera_, extract);
  const bool due = close && static_cast<int>(map->numKeyframes()) > options_.min_keyframe_gap;
  if (!places_ && !due) {
    pending_.push_back(Pending{id, kf->T_w_c, std::move(features)});
    return result;
  }
  if (!places_) {
    places_ = std::make_unique<PlaceDatabase>(camera_, options_.place);
    for (Pending& p : pending_) places_->add(p.id, p.T_w_k, std::move(p.features));
    pending_.clear();
  }
  // Bundle adjustment and earlier closures moved the keyframes since they were added.
  for (const auto& [kid, other] : map->keyframes()) places_->setPose(kid, other->T_w_c);
  if (due) {
    PlaceExclusion exclusion;
    exclusion.newest = id - options_.min_keyframe_gap;
    exclusion.ids = keyframesSharingPoints(*map, *kf);
    const PlaceMatch match = recognise(*map, *kf, features, exclusion, &result);
    result.tried = true;
    result.place = match.status;
    ++counters_.queries;
    if (match.status == PlaceStatus::kInconsistentWithOdometry) ++counters_.beyond_drift;
    if (match.status == PlaceStatus::kAmbiguous) ++counters_.ambiguous;
    if (match.recognised()) {
      ++counters_.recognised;
      result.with = match.best.keyframe;
      result.T_with_query = match.best.T_k_q;
      result.with_utime = map->keyframe(result.with)->utime;
      result.query_utime = kf->utime;
    }
    result.recognise_ms = loopMsSince(start);
    if (match.recognised()) {
      PoseGraphEdge loop;
      loop.from = match.best.keyframe;
      loop.to = id;
      loop.T_a_b = match.best.T_k_q;
      loop.sigma_t = Vec3::Constant(std::max(match.best.sigma.translation_m, options_.loop_sigma_min_m));
      loop.sigma_r = Vec3::Constant(std::max(match.best.sigma.rotation_deg, options_.loop_sigma_min_deg) / kLoopDegPerRad);
      loop.kind = PoseGraphEdgeKind::kLoop;
      const Keyframe* from = map->keyframe(loop.from);
      const PoseGraphEdgeResidual before =
          poseGraphEdgeResidual(loop, from->T_w_c, kf->T_w_c, options_.graph.disagree_sigmas);
      // Within one part only: across parts the poses are in different frames, and a join
      // always moves the newer part.
      result.same_part = from->part == kf->part;
      result.disagreement_sigmas = before.whitened_norm;
      result.disagreement_m = before.translation_m;
      result.disagreement_deg = before.rotation_deg;
      result.agreed = result.same_part && options_.agree_sigmas > 0.0 && before.whitened_norm <= options_.agree_sigmas;
      if (result.agreed) {
        ++counters_.agreed;
        loops_.push_back(loop);
      } else {
        solveAndApply(map, loop, changes, &result);
      }
      if (recognised_.size() < kMaxRecognisedKept) recognised_.push_back(result);
    }
  }
  places_->add(id, map->keyframe(id)->T_w_c, std::move(features));
  return result;
}

// The pose graph with the new loop edge 'loop': solved, loop edges that disagree with the
// solution dropped and solved again (the new one among them: refused), then applied.
void LoopCloser::solveAndApply(Map* map, const PoseGraphEdge& loop, MapChanges* changes, LoopClosureResult* result) {
  const auto graph_start = LoopClock::now();
  PoseGraph graph = buildGraph(*map, loop);
  PoseGraphResult solved = optimisePoseGraph(graph, options_.graph);
  // Loop edges that disagree with the solution are dropped, and the graph solved again.
  if (solved.ok() && solved.loop_edges_disagreeing > 0) {
    PoseGraph kept;
    kept.nodes = graph.nodes;
    for (size_t i = 0; i < graph.edges.size(); ++i) {
      if (!solved.edges[i].disagrees || graph.edges[i].kind != PoseGraphEdgeKind::kLoop) kept.edges.push_back(graph.edges[i]);
    }
    const bool new_edge_kept = !solved.edges.back().disagrees;
    graph = std::move(kept);
    solved = new_edge_kept ? optimisePoseGraph(graph, options_.graph) : PoseGraphResult{};
    result->refused = !new_edge_kept;
  }
  result->graph_ms = loopMsSince(graph_start);
  if (result->refused || !solved.ok()) {
    ++counters_.refused;
    result->refused = true;
    result->joined_part = result->joined_to = -1;
  } else {
    loops_.clear();
    for (const PoseGraphEdge& e : graph.edges) {
      if (e.kind == PoseGraphEdgeKind::kLoop) loops_.push_back(e);
    }
    if (apply(map, solved, graph, changes, result)) ++counters_.closed;
    if (result->joined_part >= 0) joinParts(map, result->joined_part, result->joined_to, changes);
  }
}

namespace {

// Appends to a log line of 'size' bytes written up to *n (a full line stays as it is).
__attribute__((format(printf, 4, 5))) void appendToLine(char* line, size_t size, int* n, const char* format, ...) {
  if (*n < 0 || *n >= static_cast<int>(size)) return;
  va_list args;
  va_start(args, format);
  const int added = std::vsnprintf(line + *n, size - *n, format, args);
  va_end(args);
  *n = added < 0 ? added : *n + added;
}

}  // namespace

std::string describe(const LoopClosureResult& r) {
  if (r.place != PlaceStatus::kRecognised) return "";
  char line[512];
  const char* verdict = r.agreed ? "agreed" : r.refused ? "refused" : r.closed ? "closed" : "below min_correction";
  int n = std::snprintf(line, sizeof line, "loop with keyframe %lld: %s", static_cast<long long>(r.with), verdict);
  if (r.same_part) {  // across parts the frames differ
    appendToLine(line, sizeof line, &n, ", disagreement %.1f sigmas (%.3f m, %.2f deg)", r.disagreement_sigmas,
                 r.disagreement_m, r.disagreement_deg);
  }
  if (r.closed) appendToLine(line, sizeof line, &n, ", correction %.3f m, %.2f deg", r.correction_m, r.correction_deg);
  if (r.joined_part >= 0) {
    appendToLine(line, sizeof line, &n, ", part %lld joined to %lld", static_cast<long long>(r.joined_part),
                 static_cast<long long>(r.joined_to));
  }
  const Vec3 t = r.T_with_query.translation();
  const Eigen::Quaterniond& q = r.T_with_query.rotation();
  appendToLine(line, sizeof line, &n, "; edge utime %lld -> %lld t %.6f %.6f %.6f q %.9f %.9f %.9f %.9f",
               static_cast<long long>(r.with_utime), static_cast<long long>(r.query_utime), t.x(), t.y(), t.z(), q.x(),
               q.y(), q.z(), q.w());
  return line;
}

// Place recognition within the keyframe's part first, with the odometry check; failing
// that, in the other parts of the map, where odometry says nothing (a part's place relative
// to the others is a guess: mapper.h, "Parts"), so the join is held to the speed the
// vehicle can fly instead (partJoinWithinReach).
PlaceMatch LoopCloser::recognise(const Map& map, const Keyframe& kf, const Features3d& features,
                                 const PlaceExclusion& exclusion, LoopClosureResult* result) {
  if (features.size() < 3) return places_->recognise(features, exclusion, kf.T_w_c);
  std::vector<PlaceCandidate> same, other;
  for (const PlaceCandidate& c : places_->query(features, exclusion)) {
    const Keyframe* candidate = map.keyframe(c.keyframe);
    if (candidate && candidate->part != kf.part) other.push_back(c);
    else same.push_back(c);
  }
  PlaceMatch match = places_->verify(features, same, kf.T_w_c);
  if (match.recognised() || other.empty()) return match;
  // The newer part moves onto the older: through the query if it is the query's, else
  // through the candidate. Each other part on its own (poses in different parts' frames
  // cannot be compared), the oldest first.
  std::map<KeyframeId, std::vector<PlaceCandidate>> by_part;
  for (const PlaceCandidate& c : other) by_part[map.keyframe(c.keyframe)->part].push_back(c);
  PlaceMatch across;
  for (const auto& [part, candidates] : by_part) {
    const KeyframeId newer = std::max(kf.part, part), older = std::min(kf.part, part);
    const bool query_moves = kf.part == newer;
    const auto plausible = [&map, &kf, query_moves, newer, older, this](KeyframeId, const SE3& T_w_q) {
      const SE3 moved = query_moves ? T_w_q * kf.T_w_c.inverse() : kf.T_w_c * T_w_q.inverse();
      return partJoinWithinReach(map, newer, older, moved);
    };
    across = places_->verify(features, candidates, std::nullopt, plausible);
    if (across.recognised()) {
      result->joined_part = newer;
      result->joined_to = older;
      return across;
    }
  }
  const bool refused = across.status == PlaceStatus::kInconsistentWithOdometry || across.status == PlaceStatus::kAmbiguous;
  return refused || match.status == PlaceStatus::kNoCandidate ? across : match;
}

// The newer part's first keyframe, moved by 'moved' into the frame of the part 'onto', must
// lie within the distance the vehicle can have flown since that part's last keyframe before
// it (join_max_speed_m_s, plus join_margin_m for the poses' own errors): the same bound as the
// tracker's relocaliser, and the only one against a lookalike place in another part. A part
// that started before 'onto' had a keyframe has no such bound: refused.
bool LoopCloser::partJoinWithinReach(const Map& map, KeyframeId part, KeyframeId onto, const SE3& moved) const {
  const Keyframe* first = nullptr;
  const Keyframe* before = nullptr;  // the last keyframe of the part it joins before it started
  for (const auto& [id, kf] : map.keyframes()) {
    if (kf->part == part && !first) first = kf.get();
    if (!first && kf->part == onto) before = kf.get();
  }
  if (!first || options_.join_max_speed_m_s <= 0.0) return first != nullptr;
  if (!before) return false;  // started before that part: no bound to hold it to
  const double dt_s = std::max(0.0, static_cast<double>(first->utime - before->utime) * 1e-6);
  const double reach_m = options_.join_max_speed_m_s * dt_s + options_.join_margin_m;
  return ((moved * first->T_w_c).translation() - before->T_w_c.translation()).norm() <= reach_m;
}

// After a join the two parts are one: the newer one's keyframes take the older one's name.
void LoopCloser::joinParts(Map* map, KeyframeId newer, KeyframeId older, MapChanges* changes) {
  for (const auto& [id, kf] : map->keyframes()) {
    if (kf->part != newer) continue;
    kf->part = older;
    changes->keyframes.insert(id);  // the rename is published even where nothing moved
  }
  ++counters_.parts_joined;
}

void LoopCloser::onKeyframeRemoved(KeyframeId id) {
  if (places_) places_->remove(id);
  loaded_.erase(id);
  pending_.erase(std::remove_if(pending_.begin(), pending_.end(), [id](const Pending& p) { return p.id == id; }),
                 pending_.end());
  loops_.erase(std::remove_if(loops_.begin(), loops_.end(),
                              [id](const PoseGraphEdge& e) { return e.from == id || e.to == id; }),
               loops_.end());
}

// Odometry edges between consecutive keyframes at their current relative poses, with sigmas
// for the drift a step may carry; the loop edges accepted before, and 'loop' last.
PoseGraph LoopCloser::buildGraph(const Map& map, const PoseGraphEdge& loop) const {
  PoseGraph graph;
  std::map<KeyframeId, const Keyframe*> last_in_part;  // odometry runs within a part
  for (const auto& [id, kf] : map.keyframes()) {
    const Keyframe*& previous = last_in_part[kf->part];
    graph.nodes.push_back(PoseGraphNode{id, kf->T_w_c, false});
    if (previous) {
      PoseGraphEdge edge;
      edge.from = previous->id;
      edge.to = id;
      edge.T_a_b = previous->T_w_c.inverse() * kf->T_w_c;
      const double step_m = edge.T_a_b.translation().norm();
      edge.sigma_t = Vec3::Constant(std::max(options_.odometry_sigma_min_m, options_.odometry_sigma_fraction * step_m));
      edge.sigma_r = Vec3::Constant(
          std::max(options_.odometry_sigma_min_deg, options_.odometry_sigma_deg_per_m * step_m) / kLoopDegPerRad);
      edge.kind = PoseGraphEdgeKind::kOdometry;
      graph.edges.push_back(edge);
    }
    previous = kf.get();
  }
  for (const PoseGraphEdge& e : loops_) {
    if (map.hasKeyframe(e.from) && map.hasKeyframe(e.to)) graph.edges.push_back(e);
  }
  graph.edges.push_back(loop);
  fixOldestOfEachComponent(&graph);
  for (PoseGraphNode& node : graph.nodes) node.fixed = node.fixed || loaded_.count(node.id) > 0;
  return graph;
}

// The solution into the map, if it moves some keyframe by more than min_correction_*: every
// keyframe to its new pose, every point with its source keyframe (movePointsWithKeyframes).
bool LoopCloser::apply(Map* map, const PoseGraphResult& solved, const PoseGraph& graph, MapChanges* changes,
                       LoopClosureResult* result) const {
  std::vector<KeyframePose> before;
  before.reserve(graph.nodes.size());
  for (size_t i = 0; i < graph.nodes.size(); ++i) {
    before.push_back(KeyframePose{graph.nodes[i].id, graph.nodes[i].T_w_k});
    result->correction_m = std::max(result->correction_m, (solved.poses[i].T_w_c.translation() - graph.nodes[i].T_w_k.translation()).norm());
    result->correction_deg = std::max(result->correction_deg, loopAngleDeg(solved.poses[i].T_w_c * graph.nodes[i].T_w_k.inverse()));
  }
  if (result->correction_m <= options_.min_correction_m && result->correction_deg <= options_.min_correction_deg) {
    return false;
  }
  for (const KeyframePose& pose : solved.poses) {
    map->keyframe(pose.id)->T_w_c = pose.T_w_c;
    changes->keyframes.insert(pose.id);
  }
  std::vector<MapPointData> points;
  points.reserve(map->numPoints());
  for (const auto& [pid, point] : map->points()) points.push_back(point.data());
  movePointsWithKeyframes(before, solved.poses, &points);
  for (const MapPointData& p : points) {
    MapPoint* point = map->point(p.id);
    if (point->p_w == p.p_w) continue;
    point->p_w = p.p_w;
    changes->points.insert(p.id);
  }
  result->closed = true;
  return true;
}

}  // namespace rgbdslam
