#include "rgbdslam/tracking/point_projection.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <optional>

namespace rgbdslam {

void makeKeyframeViews(const Map& map, const SE3& T_c_w, std::vector<KeyframeView>* views) {
  views->clear();
  if (map.keyframes().empty()) return;
  views->resize(static_cast<size_t>(map.keyframes().rbegin()->first) + 1);
  const Mat3 R_c_w = T_c_w.rotationMatrix();
  for (const auto& [id, keyframe] : map.keyframes()) {
    if (id < 0) continue;
    KeyframeView& view = (*views)[static_cast<size_t>(id)];
    const SE3 T_src_w = keyframe->T_c_w();
    const Mat3 R_src_w = T_src_w.rotationMatrix();
    view.valid = !keyframe->cold();  // a cold keyframe's points have no source image now
    view.cold = keyframe->cold();
    view.R_cur_src = R_c_w * R_src_w.transpose();
    view.src_z_row = R_src_w.row(2);
    view.src_z_offset = T_src_w.translation().z();
    view.centre_c = T_c_w * keyframe->T_w_c.translation();
  }
}

bool initSlot(const Map& map, const PinholeCamera& camera, MapPoint* point, PointSlot* slot) {
  const Keyframe* source = map.keyframe(point->source_keyframe);
  if (!source) return false;
  slot->point = point;
  slot->source = source;
  if (camera.hasDistortion()) {
    Eigen::Matrix2d d_uv_d_m;
    camera.distortAndScale(camera.unprojectToPlane(point->source_uv), &d_uv_d_m);
    slot->d_m_d_uvsrc = d_uv_d_m.inverse();
  } else {
    slot->d_m_d_uvsrc << 1.0 / camera.fx, 0.0, 0.0, 1.0 / camera.fy;
  }
  slot->patch_level = -1;
  slot->searched = slot->found = false;
  return true;
}

bool inView(const PinholeCamera& camera, const SE3& T_c_w, const Vec3& p_w, const ProjectionOptions& options) {
  const Vec3 p_c = T_c_w * p_w;
  if (p_c.z() < options.min_depth_m) return false;
  const auto uv = camera.project(p_c);
  return uv && camera.inImage(*uv, options.margin_px);
}

bool sphereMayBeInView(const PinholeCamera& camera, const SE3& T_c_w, const Vec3& centre_w, double radius_m,
                       const ProjectionOptions& options) {
  const Vec3 c = T_c_w * centre_w;
  if (c.z() + radius_m < options.min_depth_m) return false;
  if (camera.hasDistortion() || !(camera.fx > 0.0) || !(camera.fy > 0.0)) return true;
  // In the image (with any margin >= 0) needs, at z > 0, x / z <= hi = (width - cx) / fx, a
  // little wider than the last column: the half-space x - hi z <= 0. The sphere lies wholly
  // outside it when its centre's distance from the plane x - hi z = 0 exceeds the radius.
  // Likewise x / z >= lo (lo z - x <= 0), and y.
  const auto outside = [&](double along, double slope, double sign) {
    return sign * (along - slope * c.z()) > radius_m * std::sqrt(1.0 + slope * slope);
  };
  const double x_lo = (-1.0 - camera.cx) / camera.fx, x_hi = (camera.width - camera.cx) / camera.fx;
  const double y_lo = (-1.0 - camera.cy) / camera.fy, y_hi = (camera.height - camera.cy) / camera.fy;
  return !(outside(c.x(), x_hi, 1.0) || outside(c.x(), x_lo, -1.0) || outside(c.y(), y_hi, 1.0) ||
           outside(c.y(), y_lo, -1.0));
}

bool projectPoint(const PinholeCamera& camera, const SE3& T_c_w,
                  const std::vector<KeyframeView>& views, const ProjectionOptions& options,
                  PointSlot* slot) {
  slot->search_level = -1;
  const MapPoint& point = *slot->point;
  slot->p_c = T_c_w * point.p_w;
  if (slot->p_c.z() < options.min_depth_m) return false;
  Eigen::Matrix<double, 2, 3> d_uv_d_pc;
  const auto uv = camera.project(slot->p_c, &d_uv_d_pc);
  if (!uv || !camera.inImage(*uv, options.margin_px)) return false;
  slot->uv = *uv;
  const auto kf = static_cast<size_t>(point.source_keyframe);
  if (kf >= views.size() || !views[kf].valid) return false;
  const KeyframeView& view = views[kf];
  const double z_src = view.src_z_row.dot(point.p_w) + view.src_z_offset;
  if (!(z_src > options.min_depth_m)) return false;
  if (options.max_view_angle_deg > 0.0) {
    const Vec3 from_src = slot->p_c - view.centre_c;  // both rays in the current camera's frame
    const double cos_angle = slot->p_c.dot(from_src) / (slot->p_c.norm() * from_src.norm());
    if (!(cos_angle >= std::cos(options.max_view_angle_deg * M_PI / 180.0))) return false;
  }
  // A source-pixel step on the fronto-parallel plane at depth z_src moves the point by
  // z_src * d_m_d_uv in the source camera (x, y); seen from here through R_cur_src.
  const Eigen::Matrix<double, 3, 2> d_psrc_d_uvsrc =
      (Eigen::Matrix<double, 3, 2>() << z_src * slot->d_m_d_uvsrc, 0.0, 0.0).finished();
  slot->A_cur_src.noalias() = d_uv_d_pc * (view.R_cur_src * d_psrc_d_uvsrc);
  slot->search_level = chooseSearchLevel(slot->A_cur_src, point.source_level,
                                         slot->source->pyramid.numLevels());
  return slot->search_level >= 0;
}

bool ensurePatch(PointSlot* slot, double tolerance) {
  if (slot->patch_level == slot->search_level && slot->patch_cache &&
      (slot->A_cur_src - slot->patch_cache->A).cwiseAbs().maxCoeff() <= tolerance) {
    return true;
  }
  const MapPoint& point = *slot->point;
  const int source_level = point.source_level;
  if (source_level >= slot->source->pyramid.numLevels()) return false;
  if (!slot->patch_cache) slot->patch_cache = std::make_unique<PointSlot::PatchCache>();
  if (!warpPatch(slot->source->pyramid.levels[source_level], source_level, point.source_uv,
                 slot->A_cur_src, slot->search_level, &slot->patch_cache->patch)) {
    slot->patch_level = -1;
    return false;
  }
  slot->patch_cache->A = slot->A_cur_src;
  slot->patch_level = slot->search_level;
  return true;
}

}  // namespace rgbdslam

namespace rgbdslam {

int patchAcceptance(const Patch& patch, const PointSearchOptions& options) {
  const double energy =
      patch.sum_sq - static_cast<double>(patch.sum) * patch.sum / kPatchArea;
  const int accepted = std::max(options.max_zmssd_per_pixel * kPatchArea,
                                static_cast<int>(options.max_zmssd_energy_ratio * energy));
  if (options.max_zmssd_flat_ratio <= 0.0) return accepted;
  return std::min(accepted, static_cast<int>(options.max_zmssd_flat_ratio * energy));
}

namespace {

// The pixel within 'radius' [px] (Euclidean) of 'predicted' whose ZMSSD is smallest and
// below max_zmssd; nullopt if none.
std::optional<cv::Point2i> searchDense(const Patch& patch, const cv::Mat& image,
                                       const Eigen::Vector2d& predicted, int radius,
                                       int max_zmssd) {
  const int cx = static_cast<int>(std::lround(predicted.x()));
  const int cy = static_cast<int>(std::lround(predicted.y()));
  const double radius_sq = static_cast<double>(radius) * radius;
  int best = max_zmssd;
  std::optional<cv::Point2i> best_position;
  for (int y = cy - radius; y <= cy + radius; ++y) {
    for (int x = cx - radius; x <= cx + radius; ++x) {
      const double dx = x - predicted.x(), dy = y - predicted.y();
      const cv::Point2i p(x, y);
      if (dx * dx + dy * dy > radius_sq || !patchInImage(image, p)) continue;
      const int score = zmssdAt(patch, image, p);
      if (score < best) {
        best = score;
        best_position = p;
      }
    }
  }
  return best_position;
}

}  // namespace

void ProjectionOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "image_margin_px", &margin_px, 0, 100, "px",
          "projected points closer than this to the image border are not searched");
  r->bind(s, "max_view_angle_deg", &max_view_angle_deg, 0.0, 180.0, "deg",
          "points seen from a direction farther than this from their source keyframe's are not searched (0: any)");
}

void PointSearchOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "max_zmssd_per_pixel", &max_zmssd_per_pixel, 1, 65025, "grey^2",
          "patch match accepted when ZMSSD / 64 is below this");
  r->bind(s, "max_zmssd_energy_ratio", &max_zmssd_energy_ratio, 0.0, 2.0, "",
          "...or when ZMSSD is below this times the template's zero-mean energy (0: off)");
  r->bind(s, "max_zmssd_flat_ratio", &max_zmssd_flat_ratio, 0.0, 2.0, "",
          "...and in any case only when ZMSSD is below this times the template's zero-mean "
          "energy, which a textureless image patch exceeds (0: off)");
  r->bind(s, "search_dense_fallback", &dense_fallback,
          "no FAST corner in the search radius matches: test every pixel in it");
  r->bind(s, "patch_cache_tolerance", &patch_cache_tolerance, 0.0, 1.0, "",
          "re-warp a cached patch when an entry of its warp matrix changed by more");
}

int searchPoints(const std::vector<PointSlot*>& slots, const ImagePyramid& pyramid,
                 const std::vector<LevelCorners>& corners, int radius_px,
                 const PointSearchOptions& options) {
  int found = 0;
  for (PointSlot* slot : slots) {
    slot->found = false;
    slot->searched = false;
    const int level = slot->search_level;
    if (level < 0 || level >= pyramid.numLevels() || level >= static_cast<int>(corners.size())) {
      continue;
    }
    if (!ensurePatch(slot, options.patch_cache_tolerance)) continue;
    slot->searched = true;
    const Eigen::Vector2d predicted_level = levelFromZero(slot->uv, level);
    const cv::Mat& image = pyramid.levels[level];
    const Patch& patch = slot->patch();
    const int max_zmssd = patchAcceptance(patch, options);
    auto match = searchPatch(patch, image, corners[level], predicted_level,
                             radius_px, max_zmssd);
    if (!match && options.dense_fallback) {
      match = searchDense(patch, image, predicted_level, radius_px, max_zmssd);
    }
    if (!match) continue;
    Eigen::Vector2d position(match->x, match->y);
    if (!refineSubpixel(patch, image, &position, options.subpixel)) continue;
    slot->found = true;
    slot->found_uv = zeroFromLevel(position, level);
    slot->found_level = level;
    ++found;
  }
  return found;
}

}  // namespace rgbdslam
