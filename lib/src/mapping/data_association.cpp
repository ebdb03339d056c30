#include "rgbdslam/mapping/data_association.h"

#include <algorithm>

#include "rgbdslam/image/patch.h"

namespace rgbdslam {

int flatCappedAcceptance(const Patch& patch, int max_zmssd, double flat_ratio) {
  if (flat_ratio <= 0.0) return max_zmssd;
  const double energy = patch.sum_sq - static_cast<double>(patch.sum) * patch.sum / kPatchArea;
  return std::min(max_zmssd, static_cast<int>(flat_ratio * energy));
}

int PatchMatchOptions::acceptance(const Patch& patch) const {
  return flatCappedAcceptance(patch, max_zmssd_per_pixel * kPatchArea, max_zmssd_flat_ratio);
}

void PatchMatchOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "max_zmssd_per_pixel", &max_zmssd_per_pixel, 1, 65025, "grey^2",
          "patch acceptance (ZMSSD / 64) for epipolar search and re-finding");
  r->bind(s, "max_zmssd_flat_ratio", &max_zmssd_flat_ratio, 0.0, 2.0, "-",
          "...and below this times the template's zero-mean energy, which a textureless patch "
          "exceeds (0: off)");
}

void RefindOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "refind_search_radius_px", &search_radius_px, 1, 50, "level px",
          "re-finding: search radius around the prediction");
}

std::optional<Eigen::Matrix2d> patchWarp(const MapPoint& point, const Keyframe& source,
                                         const Keyframe& target, const PinholeCamera& camera) {
  const Vec3 p_s = source.T_c_w() * point.p_w;
  if (p_s.z() <= 0.0) return std::nullopt;
  const SE3 T_t_s = target.T_c_w() * source.T_w_c;
  const auto centre = camera.project(T_t_s * p_s);
  if (!centre) return std::nullopt;
  Eigen::Matrix2d A;
  for (int axis = 0; axis < 2; ++axis) {
    Eigen::Vector2d uv = point.source_uv;
    uv[axis] += 1.0;
    const auto moved = camera.project(T_t_s * camera.unproject(uv, p_s.z()));
    if (!moved) return std::nullopt;
    A.col(axis) = *moved - *centre;
  }
  return A;
}

std::optional<Measurement> findPointInKeyframe(const MapPoint& point, const Keyframe& source,
                                               const Keyframe& target, const PinholeCamera& camera,
                                               const RefindOptions& options,
                                               const PatchMatchOptions& matching) {
  const auto predicted = camera.project(target.T_c_w() * point.p_w);
  if (!predicted || !camera.inImage(*predicted, options.border_px)) return std::nullopt;
  const auto A = patchWarp(point, source, target, camera);
  if (!A) return std::nullopt;
  const int level = chooseSearchLevel(*A, point.source_level, target.pyramid.numLevels());
  if (level < 0 || level >= static_cast<int>(target.corners.size())) return std::nullopt;
  Patch patch;
  if (!warpPatch(source.pyramid.levels[point.source_level], point.source_level, point.source_uv,
                 *A, level, &patch)) {
    return std::nullopt;
  }
  const cv::Mat& image = target.pyramid.levels[level];
  const auto found = searchPatch(patch, image, target.corners[level], levelFromZero(*predicted, level),
                                 options.search_radius_px, matching.acceptance(patch));
  if (!found) return std::nullopt;
  Eigen::Vector2d pos(found->x, found->y);
  if (!refineSubpixel(patch, image, &pos)) return std::nullopt;
  return Measurement{point.id, zeroFromLevel(pos, level), level, 0.0};
}

}  // namespace rgbdslam
