#include "rgbdslam/model/point_creation.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "rgbdslam/image/corners.h"

namespace rgbdslam {

void DepthPointOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "depth_points_per_level", &max_points_per_level, 0, 100000, "points",
          "new points from depth per keyframe and pyramid level at most");
  r->bind(s, "depth_points_min_shi_tomasi", &min_shi_tomasi, 0.0, 1e6, "(grey/px)^2",
          "weaker corners give no point");
  r->bind(s, "depth_points_weak_noise_ratio", &weak_noise_ratio, 0.0, 1e6, "",
          "a keyframe with few points also takes corners down to this multiple of the score "
          "its image noise gives...");
  r->bind(s, "depth_points_weak_min_shi_tomasi", &weak_min_shi_tomasi, 0.0, 1e6, "(grey/px)^2",
          "...but not below this score...");
  r->bind(s, "depth_points_weak_until_points", &weak_until_points, 0, 100000, "points",
          "...until it measures this many points (0: never)");
  r->bind(s, "depth_points_min_separation_px", &min_separation_px, 0.0, 100.0, "px",
          "new points keep this distance from measured points and each other");
  r->bind(s, "depth_points_discontinuity", &depth_discontinuity, 0.0, 1.0, "fraction",
          "a spread of the 3x3 window's depths above this (relative to the corner's) rejects the corner");
  r->bind(s, "depth_points_dense_fraction", &dense_depth_fraction, 0.0, 1.0, "fraction",
          "with at least this fraction of pixels valid, a missing 3x3 neighbour rejects a corner");
}
namespace {

// Occupancy grid over level-0 pixels with cells of min_separation: a corner is rejected
// when an occupied point lies within min_separation.
class SeparationGrid {
 public:
  SeparationGrid(int width, int height, double separation)
      : cell_(std::max(1.0, separation)), separation2_(separation * separation),
        cols_(static_cast<int>(width / cell_) + 1), rows_(static_cast<int>(height / cell_) + 1),
        cells_(static_cast<size_t>(cols_ * rows_)) {}

  bool isFree(const Eigen::Vector2d& uv) const {
    const int cx = cellX(uv), cy = cellY(uv);
    for (int y = std::max(0, cy - 1); y <= std::min(rows_ - 1, cy + 1); ++y) {
      for (int x = std::max(0, cx - 1); x <= std::min(cols_ - 1, cx + 1); ++x) {
        for (const auto& other : cells_[y * cols_ + x]) {
          if ((other - uv).squaredNorm() < separation2_) return false;
        }
      }
    }
    return true;
  }
  void occupy(const Eigen::Vector2d& uv) {
    const int cx = std::clamp(cellX(uv), 0, cols_ - 1), cy = std::clamp(cellY(uv), 0, rows_ - 1);
    cells_[cy * cols_ + cx].push_back(uv);
  }

 private:
  int cellX(const Eigen::Vector2d& uv) const { return static_cast<int>(uv.x() / cell_); }
  int cellY(const Eigen::Vector2d& uv) const { return static_cast<int>(uv.y() / cell_); }
  double cell_, separation2_;
  int cols_, rows_;
  std::vector<std::vector<Eigen::Vector2d>> cells_;
};

// Depth at a level-0 pixel if it has a reading and the readings around it in the 3x3
// window agree with it (a corner on a depth edge would get the depth of either side).
// In dense depth a missing neighbour marks an edge or a hole (occlusion shadow, glass), so
// it rejects the corner ('require_all'); in sparse depth readings are missing everywhere
// and carry no such meaning, so missing neighbours are ignored.
std::optional<double> stableDepth(const KeyframeDepth& depth, const Eigen::Vector2d& uv, double max_spread,
                                  bool require_all) {
  const int u = static_cast<int>(std::lround(uv.x())), v = static_cast<int>(std::lround(uv.y()));
  if (u < 1 || v < 1 || u >= depth.cols() - 1 || v >= depth.rows() - 1) return std::nullopt;
  const float centre = depth.at(u, v);
  if (!std::isfinite(centre)) return std::nullopt;
  float lo = centre, hi = centre;
  for (int dv = -1; dv <= 1; ++dv) {
    for (int du = -1; du <= 1; ++du) {
      const float d = depth.at(u + du, v + dv);
      if (!std::isfinite(d)) {
        if (require_all) return std::nullopt;
        continue;
      }
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
  }
  if (hi - lo > max_spread * centre) return std::nullopt;
  return centre;
}

struct Candidate {
  float score;
  cv::Point2i corner;
};

// One pass over the levels: the keyframe's maxima with Shi-Tomasi score >= min_score[level],
// strongest first per level, that are free in 'grid' and have a stable depth.
void addPointsFromDepth(const Keyframe& keyframe, const PinholeCamera& camera,
                        const DepthPointOptions& options, const std::vector<double>& min_score,
                        size_t max_total,
                        PointId first_id, bool dense, SeparationGrid* grid,
                        std::vector<NewPoint>* created) {
  for (int level = 0; level < static_cast<int>(keyframe.corners.size()); ++level) {
    const cv::Mat& image = keyframe.pyramid.levels[level];
    std::vector<Candidate> candidates;
    for (const cv::Point2i& c : keyframe.corners[level].maxima) {
      if (c.x < options.patch_border_px || c.y < options.patch_border_px ||
          c.x >= image.cols - options.patch_border_px || c.y >= image.rows - options.patch_border_px) {
        continue;
      }
      const float score = shiTomasiScore(image, c);
      if (score >= min_score[level]) candidates.push_back({score, c});
    }
    std::sort(candidates.begin(), candidates.end(),
              [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
    int added = 0;
    for (const Candidate& cand : candidates) {
      if (added >= options.max_points_per_level || created->size() >= max_total) break;
      const Eigen::Vector2d uv = zeroFromLevel(Eigen::Vector2d(cand.corner.x, cand.corner.y), level);
      if (!grid->isFree(uv)) continue;
      const auto depth = stableDepth(keyframe.depth, uv, options.depth_discontinuity, dense);
      if (!depth) continue;
      const PointId id = first_id + static_cast<PointId>(created->size());
      NewPoint np;
      np.point = MapPoint(MapPointData{id, keyframe.T_w_c * camera.unproject(uv, *depth),
                                       keyframe.id, uv, level});
      np.measurement = Measurement{id, uv, level, *depth};
      created->push_back(np);
      grid->occupy(uv);
      ++added;
    }
  }
}

}  // namespace

std::vector<NewPoint> createPointsFromDepth(const Keyframe& keyframe, const PinholeCamera& camera,
                                            const DepthPointOptions& options, PointId first_id) {
  std::vector<NewPoint> created;
  if (keyframe.depth.empty()) return created;
  SeparationGrid grid(camera.width, camera.height, options.min_separation_px);
  for (const auto& [point_id, m] : keyframe.measurements()) grid.occupy(m.uv);
  const bool dense = keyframe.depth.validFraction() >= options.dense_depth_fraction;
  const size_t levels = keyframe.corners.size();
  addPointsFromDepth(keyframe, camera, options, std::vector<double>(levels, options.min_shi_tomasi),
                     SIZE_MAX, first_id, dense, &grid, &created);
  const size_t measured = keyframe.measurements().size() + created.size();
  const size_t wanted = static_cast<size_t>(std::max(0, options.weak_until_points));
  if (measured >= wanted) return created;
  const std::vector<double> floors = weakScoreFloors(keyframe.pyramid, options);
  // No level with a floor under min_shi_tomasi: the second pass would only see the strong
  // corners again, and could retake those a level's max_points_per_level cut (the count
  // restarts per pass), which is not what it is for.
  if (std::none_of(floors.begin(), floors.end(), [&](double f) { return f < options.min_shi_tomasi; })) return created;
  addPointsFromDepth(keyframe, camera, options, floors, created.size() + (wanted - measured), first_id, dense,
                     &grid, &created);
  return created;
}

std::vector<double> weakScoreFloors(const ImagePyramid& pyramid, const DepthPointOptions& options) {
  std::vector<double> floors(pyramid.levels.size(), options.min_shi_tomasi);
  if (pyramid.levels.empty()) return floors;
  // Level 0 has the most pixels and the least texture per pixel, so its estimate is the
  // tightest; each 2x2 average halves the noise's standard deviation.
  double sigma = imageNoiseSigma(pyramid.levels[0]);
  for (double& floor : floors) {
    const double weak = std::max(options.weak_min_shi_tomasi, options.weak_noise_ratio * noiseShiTomasiScore(sigma));
    floor = std::min(floor, weak);
    sigma *= 0.5;
  }
  return floors;
}

}  // namespace rgbdslam
