#include "rgbdslam/tracking/depth_integrity.h"

#include <algorithm>
#include <cmath>

namespace rgbdslam {

void DepthRecord::add(DepthVerdict verdict, double depth_m) {
  if (verdict == DepthVerdict::kUnchecked) return;
  if (verdict == DepthVerdict::kMissing) {
    ++missing;
    return;
  }
  ++checks;
  seen_through += verdict == DepthVerdict::kSeenThrough;
  // Only a reading of the point's own surface tells how far that surface gives readings; an
  // occluder's (nearer) or the background's (farther, seen through) does not.
  if (verdict == DepthVerdict::kAgrees) read_max_m = std::max(read_max_m, static_cast<float>(depth_m));
}

void DepthIntegrityOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "integrity_check", &enabled,
          "hold every tracked pose against the depth image (depth modes): a pose that sees through too many map points is lost, makes no keyframe, and is retried from the prediction and the last pose first");
  r->bind(s, "integrity_max_samples", &max_samples, 1, 100000, "points", "map points checked per frame at most");
  r->bind(s, "integrity_min_samples", &min_samples, 1, 100000, "points",
          "fewer checked points with a depth reading: no verdict");
  r->bind(s, "integrity_window_px", &window_px, 0, 10, "px",
          "the nearest measured surface within this of a point's projection is compared");
  r->bind(s, "integrity_free_space_sigmas", &free_space_sigmas, 0.5, 100.0, "sigmas",
          "a surface farther than the point by this many sigmas of the depth noise (reading and point) sees through it");
  r->bind(s, "integrity_free_space_min_m", &free_space_min_m, 0.0, 10.0, "m", "...and by at least this");
  r->bind(s, "integrity_max_free_space_ratio", &max_free_space_ratio, 0.0, 1.0, "",
          "a pose that sees through more than this fraction of the checked points is inconsistent");
  r->bind(s, "integrity_max_missing_ratio", &max_missing_ratio, 0.0, 1.0, "",
          "...or finds no reading near more than this fraction of the points judged, where each "
          "point's surface gave a reading at most of its accepted poses");
}

void OcclusionOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "occlusion_check", &enabled,
          "map points behind a nearer measured surface are not searched and do not count in the quality (depth modes)");
  r->bind(s, "occlusion_window_px", &window_px, 2, 20, "px",
          "every reading within this of a point's projection (every other pixel; rounded down to even) must be nearer for it to be hidden");
  r->bind(s, "occlusion_min_readings", &min_readings, 1, 441, "samples",
          "fewer of the window's samples with a reading (25 at a window of 4 px, 9 at 2): the point is searched");
  r->bind(s, "occlusion_sigmas", &sigmas, 0.5, 100.0, "sigmas",
          "hidden: the readings nearer than the point by this many sigmas of the depth noise (reading and point)");
  r->bind(s, "occlusion_min_m", &min_m, 0.0, 10.0, "m", "...and by at least this");
  r->bind(s, "occlusion_min_agreeing", &min_agreeing, 0, 100000, "points",
          "...and only after a pose tracked from the motion's prediction at which at least this many found points agreed with their depth readings (by tracker.integrity_check: off, no point is left out)");
}

bool hiddenInDepth(const Vec3& p_c, const Eigen::Vector2d& uv, const RgbdFrame& frame, const NoiseModel& noise,
                   double min_depth_m, double max_depth_m, const OcclusionOptions& options) {
  if (frame.depth.empty() || frame.depth.type() != CV_16UC1 || !(frame.depth_scale > 0) || !(p_c.z() > 0.0)) {
    return false;
  }
  const double raw_min = std::max(1.0, std::ceil(min_depth_m * frame.depth_scale));
  const double raw_max = std::min(65535.0, std::floor(max_depth_m * frame.depth_scale));
  const int u = static_cast<int>(std::lround(uv.x())), v = static_cast<int>(std::lround(uv.y()));
  const int w = options.window_px / 2 * 2;  // even: the samples, every other pixel, include (u, v)
  int readings = 0;
  uint16_t farthest = 0;
  for (int y = v - w; y <= v + w; y += 2) {
    if (y < 0 || y >= frame.depth.rows) continue;
    const uint16_t* row = frame.depth.ptr<uint16_t>(y);
    for (int x = u - w; x <= u + w; x += 2) {
      if (x < 0 || x >= frame.depth.cols || row[x] < raw_min || row[x] > raw_max) continue;
      ++readings;
      farthest = std::max(farthest, row[x]);
    }
  }
  if (readings < options.min_readings) return false;
  const double measured = farthest / frame.depth_scale, predicted = p_c.z();
  const double sigma = std::hypot(noise.sigmaDepth(measured), noise.sigmaDepth(predicted));
  return predicted - measured > std::max(options.sigmas * sigma, options.min_m);
}

std::string DepthIntegrity::describe() const {
  std::string text = std::to_string(seen_through) + " of " + std::to_string(checked) + " map points seen through in depth";
  if (missing_counted > 0) {
    text += ", " + std::to_string(missing_counted) + " of " + std::to_string(checked + missing_counted) +
            " without the reading their surface gives";
  }
  return text;
}

DepthIntegrity checkDepthIntegrity(const std::vector<Vec3>& points_w, const SE3& T_c_w,
                                   const RgbdFrame& frame, const PinholeCamera& camera,
                                   const NoiseModel& noise, double min_depth_m, double max_depth_m,
                                   const DepthIntegrityOptions& options,
                                   std::vector<DepthVerdict>* verdicts,
                                   const std::vector<uint8_t>* reading_expected) {
  DepthIntegrity out;
  if (verdicts) verdicts->assign(points_w.size(), DepthVerdict::kUnchecked);
  if (frame.depth.empty() || frame.depth.type() != CV_16UC1 || !(frame.depth_scale > 0) || points_w.empty()) return out;
  const size_t step = std::max<size_t>(1, points_w.size() / static_cast<size_t>(std::max(1, options.max_samples)));
  const uint16_t raw_min = static_cast<uint16_t>(std::clamp(std::ceil(min_depth_m * frame.depth_scale), 1.0, 65535.0));
  const uint16_t raw_max = static_cast<uint16_t>(std::clamp(std::floor(max_depth_m * frame.depth_scale), 1.0, 65535.0));
  const int w = options.window_px;
  std::vector<double> residuals;
  for (size_t i = 0; i < points_w.size(); i += step) {
    const Vec3 p_c = T_c_w * points_w[i];
    if (p_c.z() < min_depth_m) continue;
    const auto uv = camera.project(p_c);
    if (!uv || !(uv->x() >= 0.0 && uv->y() >= 0.0 && uv->x() < frame.depth.cols && uv->y() < frame.depth.rows)) continue;
    const int u = static_cast<int>(std::lround(uv->x())), v = static_cast<int>(std::lround(uv->y()));
    uint16_t nearest = 0;
    const uint16_t centre = frame.depth.at<uint16_t>(std::min(v, frame.depth.rows - 1), std::min(u, frame.depth.cols - 1));
    for (int y = std::max(0, v - w); y <= std::min(frame.depth.rows - 1, v + w); ++y) {
      const uint16_t* row = frame.depth.ptr<uint16_t>(y);
      for (int x = std::max(0, u - w); x <= std::min(frame.depth.cols - 1, u + w); ++x) {
        const uint16_t raw = row[x];
        if (raw >= raw_min && raw <= raw_max && (nearest == 0 || raw < nearest)) nearest = raw;
      }
    }
    if (nearest == 0) {
      if (p_c.z() > max_depth_m) continue;  // beyond the range: no reading is what it gives
      ++out.missing;
      if (verdicts) (*verdicts)[i] = DepthVerdict::kMissing;
      if (reading_expected && i < reading_expected->size() && (*reading_expected)[i]) ++out.missing_counted;
      continue;
    }
    const double measured = nearest / frame.depth_scale, predicted = p_c.z();
    const double sigma = std::hypot(noise.sigmaDepth(measured), noise.sigmaDepth(predicted));
    const double margin = std::max(options.free_space_sigmas * sigma, options.free_space_min_m);
    ++out.checked;
    if (centre >= raw_min && centre <= raw_max) {
      const double at_centre = centre / frame.depth_scale;
      residuals.push_back((at_centre - predicted) / std::hypot(noise.sigmaDepth(at_centre), noise.sigmaDepth(predicted)));
    }
    DepthVerdict verdict = DepthVerdict::kAgrees;
    if (measured - predicted > margin) verdict = DepthVerdict::kSeenThrough, ++out.seen_through;
    else if (predicted - measured > margin) verdict = DepthVerdict::kOccluded, ++out.occluded;
    if (verdicts) (*verdicts)[i] = verdict;
  }
  if (!residuals.empty()) {
    auto mid = residuals.begin() + static_cast<std::ptrdiff_t>(residuals.size() / 2);
    std::nth_element(residuals.begin(), mid, residuals.end());
    out.median_residual = *mid;
    for (double& r : residuals) r = std::abs(r);
    std::nth_element(residuals.begin(), mid, residuals.end());
    out.median_abs_residual = *mid;
  }
  out.judged = out.checked + out.missing_counted >= options.min_samples;
  out.consistent = !out.judged || (out.seenThroughRatio() <= options.max_free_space_ratio &&
                                    out.missingRatio() <= options.max_missing_ratio);
  return out;
}

}  // namespace rgbdslam
