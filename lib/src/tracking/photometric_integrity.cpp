#include "rgbdslam/tracking/photometric_integrity.h"

#include <algorithm>

namespace rgbdslam {

void PhotometricIntegrityOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "photometric_check", &enabled,
          "hold every tracked pose against the image: a pose that puts too many found patches where they do not match is lost, makes no keyframe, and is retried from the prediction and the last pose first");
  r->bind(s, "photometric_max_samples", &max_samples, 1, 100000, "patches", "found patches checked per frame at most");
  r->bind(s, "photometric_min_samples", &min_samples, 1, 100000, "patches", "fewer found patches: no verdict");
  r->bind(s, "photometric_max_mismatch_ratio", &max_mismatch_ratio, 0.0, 1.0, "",
          "a pose that puts more than this fraction of the checked patches where the search would not accept them is inconsistent");
}

std::string PhotometricIntegrity::describe() const {
  return std::to_string(mismatched) + " of " + std::to_string(checked) +
         " tracked patches do not match where the pose puts them";
}

PhotometricIntegrity checkPhotometricIntegrity(const std::vector<PointSlot*>& slots, const SE3& T_c_w,
                                               const ImagePyramid& pyramid, const PinholeCamera& camera,
                                               const PointSearchOptions& search,
                                               const PhotometricIntegrityOptions& options) {
  PhotometricIntegrity out;
  if (!options.enabled) return out;
  int found = 0;
  for (const PointSlot* slot : slots) found += slot->found;
  const int step = std::max(1, found / std::max(1, options.max_samples));
  int index = 0;
  for (const PointSlot* slot : slots) {
    if (!slot->found || index++ % step != 0) continue;
    const int level = slot->found_level;
    if (slot->patch_level != level || level < 0 || level >= pyramid.numLevels()) continue;
    const auto uv = camera.project(T_c_w * slot->point->p_w);
    if (!uv) continue;
    const int score = zmssdAtSubpixel(slot->patch(), pyramid.levels[static_cast<size_t>(level)], levelFromZero(*uv, level));
    if (score < 0) continue;
    const double accepted = patchAcceptance(slot->patch(), search);
    ++out.checked;
    if (score >= accepted) ++out.mismatched;
  }
  out.judged = out.checked >= options.min_samples;
  out.consistent = !out.judged || out.mismatchRatio() <= options.max_mismatch_ratio;
  return out;
}

}  // namespace rgbdslam
