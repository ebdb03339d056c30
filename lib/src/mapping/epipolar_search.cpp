#include "rgbdslam/mapping/epipolar_search.h"

#include <algorithm>
#include <climits>
#include <cstdint>
#include <cmath>
#include <tuple>

#include "rgbdslam/image/patch.h"
#include "rgbdslam/mapping/data_association.h"

namespace rgbdslam {
namespace {

constexpr int kSegmentSamples = 16;        // polyline vertices of the epipolar segment
constexpr double kMinSegmentDepth = 0.05;  // nearest depth in the other camera [m]
constexpr double kDistinctRadius2 = 4.0;   // "second best" is > 2 px from the best [px^2]

struct Candidate {
  float score;
  int level;
  cv::Point2i corner;
  Eigen::Vector2d uv0;
};

// The new keyframe's maxima with min_score <= Shi-Tomasi < max_score, strongest first (ties
// in level/row/column order).
std::vector<Candidate> collectCandidates(const Keyframe& kf, const EpipolarOptions& options,
                                         double min_score, double max_score) {
  std::vector<Candidate> out;
  for (int level = 0; level < static_cast<int>(kf.corners.size()); ++level) {
    const cv::Mat& image = kf.pyramid.levels[level];
    for (const cv::Point2i& c : kf.corners[level].maxima) {
      if (!patchInImage(image, c) || c.x < kPatchCentre + 1 || c.y < kPatchCentre + 1 ||
          c.x > image.cols - kPatchCentre - 2 || c.y > image.rows - kPatchCentre - 2) {
        continue;
      }
      const Eigen::Vector2d uv0 = zeroFromLevel(Eigen::Vector2d(c.x, c.y), level);
      if (options.skip_corners_with_depth && kf.depthAt(uv0)) continue;
      const float score = shiTomasiScore(image, c);
      if (score >= min_score && score < max_score) out.push_back({score, level, c, uv0});
    }
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
  return out;
}

bool farFromAll(const Eigen::Vector2d& uv, const std::vector<Eigen::Vector2d>& taken, double sep2) {
  for (const auto& t : taken) {
    if ((t - uv).squaredNorm() < sep2) return false;
  }
  return true;
}

double distanceToPolyline(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& line) {
  double best = INFINITY;
  for (size_t i = 0; i + 1 < line.size(); ++i) {
    const Eigen::Vector2d d = line[i + 1] - line[i];
    const double len2 = d.squaredNorm();
    const double t = len2 > 0 ? std::clamp((p - line[i]).dot(d) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, (line[i] + t * d - p).norm());
  }
  return best;
}

// The epipolar segment in 'other' at 'level' [level px], sampled uniformly in inverse depth
// over the part of the depth range in front of the other camera. Empty if none is.
std::vector<Eigen::Vector2d> epipolarSegment(const Vec3& ray_k, const SE3& T_o_k, int level,
                                             const PinholeCamera& camera,
                                             const EpipolarOptions& options) {
  std::vector<Eigen::Vector2d> line;
  const Vec3 dir_o = T_o_k.rotationMatrix() * ray_k;
  const Vec3& t_o = T_o_k.translation();
  double d_min = options.min_depth_m, d_max = options.max_depth_m;
  // z_o(d) = t_o.z + dir_o.z d must stay above kMinSegmentDepth.
  if (std::abs(dir_o.z()) > 1e-12) {
    const double d_zero = (kMinSegmentDepth - t_o.z()) / dir_o.z();
    if (dir_o.z() > 0) d_min = std::max(d_min, d_zero);
    else d_max = std::min(d_max, d_zero);
  } else if (t_o.z() < kMinSegmentDepth) {
    return line;
  }
  if (d_min >= d_max) return line;
  for (int i = 0; i <= kSegmentSamples; ++i) {
    const double inv = 1.0 / d_max + (1.0 / d_min - 1.0 / d_max) * i / kSegmentSamples;
    const auto uv = camera.project(t_o + dir_o / inv);
    if (uv) line.push_back(levelFromZero(*uv, level));
  }
  return line;
}

// Corners of 'corners' within tolerance of the polyline.
std::vector<cv::Point2i> cornersNearLine(const LevelCorners& corners,
                                         const std::vector<Eigen::Vector2d>& line, double tol) {
  std::vector<cv::Point2i> out;
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
  for (const auto& p : line) {
    x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x());
    y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
  }
  const int row_begin = std::max(0, static_cast<int>(std::floor(y0 - tol)));
  const int row_end = std::min(corners.rows(), static_cast<int>(std::ceil(y1 + tol)) + 1);
  if (row_begin >= row_end) return out;
  for (int i = corners.row_start[row_begin]; i < corners.row_start[row_end]; ++i) {
    const cv::Point2i& c = corners.all[i];
    if (c.x < x0 - tol || c.x > x1 + tol) continue;
    if (distanceToPolyline(Eigen::Vector2d(c.x, c.y), line) <= tol) out.push_back(c);
  }
  return out;
}

enum class MatchOutcome { kFound, kNoMatch, kAmbiguous };

// Best ZMSSD among the candidates, distinct from the second best (> 2 px away).
MatchOutcome bestDistinctMatch(const Patch& patch, const cv::Mat& image,
                               const std::vector<cv::Point2i>& candidates,
                               const EpipolarOptions& options, int max_zmssd, cv::Point2i* best) {
  std::vector<std::pair<int, cv::Point2i>> scored;
  for (const cv::Point2i& c : candidates) {
    if (patchInImage(image, c)) scored.emplace_back(zmssdAt(patch, image, c), c);
  }
  if (scored.empty()) return MatchOutcome::kNoMatch;
  const auto min_it = std::min_element(scored.begin(), scored.end(), [](const auto& a, const auto& b) {
    return std::tie(a.first, a.second.y, a.second.x) < std::tie(b.first, b.second.y, b.second.x);
  });
  if (min_it->first >= max_zmssd) return MatchOutcome::kNoMatch;
  int second = INT_MAX;
  for (const auto& [score, c] : scored) {
    const cv::Point2i d = c - min_it->second;
    if (d.x * d.x + d.y * d.y > kDistinctRadius2) second = std::min(second, score);
  }
  if (second != INT_MAX && min_it->first >= options.distinctiveness * second) {
    return MatchOutcome::kAmbiguous;
  }
  *best = min_it->second;
  return MatchOutcome::kFound;
}

// The cross-check (stereo's left-right consistency): the match's patch in 'other', searched
// back along its own epipolar segment in 'keyframe', finds the corner it came from (within
// 2 px at the level). A chance match on the long near end of a segment (a surface beyond
// the range, a "near ghost") mostly finds another corner.
bool matchesBack(const Keyframe& keyframe, const Keyframe& other, const PinholeCamera& camera,
                 const EpipolarOptions& options, const PatchMatchOptions& matching,
                 const Candidate& cand, const cv::Point2i& match) {
  const int level = cand.level;
  const cv::Mat& other_image = other.pyramid.levels[level];
  Patch back_patch;
  if (!extractPatch(other_image, match, &back_patch)) return false;
  const Eigen::Vector2d uv_match = zeroFromLevel(Eigen::Vector2d(match.x, match.y), level);
  const SE3 T_k_o = keyframe.T_c_w() * other.T_w_c;
  const auto line = epipolarSegment(camera.unproject(uv_match, 1.0), T_k_o, level, camera, options);
  if (line.size() < 2) return false;
  const auto near = cornersNearLine(keyframe.corners[level], line, options.line_tolerance_px);
  cv::Point2i back;
  if (bestDistinctMatch(back_patch, keyframe.pyramid.levels[level], near, options,
                        matching.acceptance(back_patch), &back) != MatchOutcome::kFound) {
    return false;
  }
  const cv::Point2i d = back - cand.corner;
  return d.x * d.x + d.y * d.y <= kDistinctRadius2;
}

// Triangulates the match and checks parallax, depth range and reprojection in both views.
std::optional<Vec3> triangulateChecked(const Keyframe& kf, const Eigen::Vector2d& uv_k,
                                       const Keyframe& other, const Eigen::Vector2d& uv_o, int level,
                                       const PinholeCamera& camera, const EpipolarOptions& options) {
  const Vec3 d_k = (kf.T_w_c.rotationMatrix() * camera.unproject(uv_k, 1.0)).normalized();
  const Vec3 d_o = (other.T_w_c.rotationMatrix() * camera.unproject(uv_o, 1.0)).normalized();
  const double parallax = std::acos(std::clamp(d_k.dot(d_o), -1.0, 1.0));
  if (parallax < options.min_parallax_deg * M_PI / 180.0) return std::nullopt;
  const auto p_w = triangulateMidpoint(kf.T_w_c.translation(), d_k, other.T_w_c.translation(), d_o);
  if (!p_w) return std::nullopt;
  const double max_error = options.max_reprojection_px * levelScale(level);
  for (const auto& [frame, uv] : {std::pair<const Keyframe*, Eigen::Vector2d>{&kf, uv_k}, {&other, uv_o}}) {
    const Vec3 p_c = frame->T_c_w() * *p_w;
    if (p_c.z() < options.min_depth_m || p_c.z() > options.max_depth_m) return std::nullopt;
    const auto projected = camera.project(p_c);
    if (!projected || (*projected - uv).norm() > max_error) return std::nullopt;
  }
  return p_w;
}

}  // namespace

std::optional<Vec3> triangulateMidpoint(const Vec3& o_a, const Vec3& d_a, const Vec3& o_b,
                                        const Vec3& d_b) {
  // Minimise |o_a + s d_a - o_b - t d_b|^2 over s, t (unit directions).
  const double c = d_a.dot(d_b);
  const double denom = 1.0 - c * c;
  if (denom < 1e-12) return std::nullopt;
  const Vec3 w = o_a - o_b;
  const double s = (c * d_b.dot(w) - d_a.dot(w)) / denom;
  const double t = (d_b.dot(w) - c * d_a.dot(w)) / denom;
  if (s <= 0.0 || t <= 0.0) return std::nullopt;
  return Vec3(0.5 * (o_a + s * d_a + o_b + t * d_b));
}

namespace {

// One pass over 'candidates' (at most options.max_points tried, and none once the keyframe
// measures stop_at_points: taken.size()), appending to 'created'.
void searchCandidates(const Keyframe& keyframe, const Keyframe& other, const PinholeCamera& camera,
                      const EpipolarOptions& options, const PatchMatchOptions& matching,
                      const std::vector<Candidate>& candidates,
                      size_t stop_at_points, PointId first_id, std::vector<Eigen::Vector2d>* taken,
                      std::vector<EpipolarPoint>* created, EpipolarStats* st) {
  const double sep2 = options.min_separation_px * options.min_separation_px;
  const SE3 T_o_k = other.T_c_w() * keyframe.T_w_c;
  int tried = 0;
  for (const Candidate& cand : candidates) {
    if (tried >= options.max_points || taken->size() >= stop_at_points) break;
    if (!farFromAll(cand.uv0, *taken, sep2)) continue;
    ++tried;
    ++st->tried;
    const int level = cand.level;
    Patch patch;
    if (!extractPatch(keyframe.pyramid.levels[level], cand.corner, &patch)) continue;
    const Vec3 ray_k = camera.unproject(cand.uv0, 1.0);
    const auto line = epipolarSegment(ray_k, T_o_k, level, camera, options);
    if (line.size() < 2) { ++st->no_candidate; continue; }
    const auto near = cornersNearLine(other.corners[level], line, options.line_tolerance_px);
    if (near.empty()) { ++st->no_candidate; continue; }
    cv::Point2i match;
    const cv::Mat& other_image = other.pyramid.levels[level];
    const MatchOutcome outcome =
        bestDistinctMatch(patch, other_image, near, options, matching.acceptance(patch), &match);
    if (outcome == MatchOutcome::kNoMatch) { ++st->no_match; continue; }
    if (outcome == MatchOutcome::kAmbiguous) { ++st->ambiguous; continue; }
    if (options.cross_check && !matchesBack(keyframe, other, camera, options, matching, cand, match)) {
      ++st->cross_check_failed;
      continue;
    }
    Eigen::Vector2d pos(match.x, match.y);
    if (!refineSubpixel(patch, other_image, &pos)) { ++st->subpixel_failed; continue; }
    const Eigen::Vector2d uv_o = zeroFromLevel(pos, level);
    const auto p_w = triangulateChecked(keyframe, cand.uv0, other, uv_o, level, camera, options);
    if (!p_w) { ++st->bad_triangulation; continue; }
    EpipolarPoint ep;
    ep.point = MapPoint(MapPointData{first_id + static_cast<PointId>(created->size()), *p_w,
                                     keyframe.id, cand.uv0, level});
    ep.in_keyframe = Measurement{ep.point.id, cand.uv0, level, 0.0};
    ep.in_other = Measurement{ep.point.id, uv_o, level, 0.0};
    created->push_back(ep);
    taken->push_back(cand.uv0);
    ++st->created;
  }
}

}  // namespace

void EpipolarOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "epipolar_min_depth_m", &min_depth_m, 0.01, 100.0, "m", "epipolar search: nearest depth along the ray");
  r->bind(s, "epipolar_max_depth_m", &max_depth_m, 0.1, 1000.0, "m", "epipolar search: farthest depth along the ray");
  r->bind(s, "epipolar_max_points", &max_points, 0, 10000, "corners", "corners without depth tried per new keyframe");
  r->bind(s, "epipolar_min_shi_tomasi", &min_shi_tomasi, 0.0, 1e6, "(grey/px)^2", "weaker corners are not tried");
  r->bind(s, "epipolar_weak_min_shi_tomasi", &weak_min_shi_tomasi, 0.0, 1e6, "(grey/px)^2", "a mono keyframe (no points from depth) with few points also tries corners down to this score...");
  r->bind(s, "epipolar_weak_until_points", &weak_until_points, 0, 100000, "points", "...until it measures this many points (0: never)");
  r->bind(s, "epipolar_min_separation_px", &min_separation_px, 0.0, 100.0, "px", "distance from points the keyframe measures (level 0)");
  r->bind(s, "epipolar_line_tolerance_px", &line_tolerance_px, 0.1, 20.0, "level px", "corner distance from the epipolar segment");
  r->bind(s, "epipolar_distinctiveness", &distinctiveness, 0.0, 1.0, "-", "best ZMSSD must be below this times the second best");
  r->bind(s, "epipolar_cross_check", &cross_check,
          "depth modes: keep a match only when its patch, searched back along its own epipolar "
          "segment, finds the corner it came from (stereo's left-right consistency; see "
          "epipolar_search.h)");
  r->bind(s, "epipolar_min_parallax_deg", &min_parallax_deg, 0.0, 90.0, "deg", "smaller ray angles do not triangulate");
  r->bind(s, "epipolar_max_reprojection_px", &max_reprojection_px, 0.1, 20.0, "level px", "triangulated point's error in either view");
}

std::vector<EpipolarPoint> epipolarSearch(const Keyframe& keyframe, const Keyframe& other,
                                          const PinholeCamera& camera, const EpipolarOptions& options,
                                          const PatchMatchOptions& matching, PointId first_id,
                                          EpipolarStats* stats) {
  EpipolarStats local;
  EpipolarStats& st = stats ? *stats : local;
  std::vector<EpipolarPoint> created;
  std::vector<Eigen::Vector2d> taken;
  for (const auto& [id, m] : keyframe.measurements()) taken.push_back(m.uv);
  searchCandidates(keyframe, other, camera, options, matching,
                   collectCandidates(keyframe, options, options.min_shi_tomasi, INFINITY), SIZE_MAX,
                   first_id, &taken, &created, &st);
  const size_t wanted = static_cast<size_t>(std::max(0, options.weak_until_points));
  if (taken.size() < wanted && options.weak_min_shi_tomasi < options.min_shi_tomasi) {
    searchCandidates(keyframe, other, camera, options, matching,
                     collectCandidates(keyframe, options, options.weak_min_shi_tomasi,
                                       options.min_shi_tomasi),
                     wanted, first_id, &taken, &created, &st);
  }
  return created;
}

}  // namespace rgbdslam
