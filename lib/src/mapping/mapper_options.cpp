#include "rgbdslam/mapping/mapper.h"

namespace rgbdslam {

void BaWindowOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "local_ba_neighbours", &local_ba_neighbours, 0, 100, "keyframes",
          "nearest keyframes optimised with a new one in local BA");
  r->bind(s, "global_ba_every", &global_ba_every, 1, 1000, "keyframes",
          "run global BA after this many new keyframes");
  r->bind(s, "max_global_ba_keyframes", &max_global_ba_keyframes, 2, 100000, "keyframes",
          "above this, global BA optimises only the newest ones");
}

void EpipolarPartnerOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "epipolar_partner_distance_ratio", &distance_ratio, 0.0, 10.0, "-",
          "epipolar partner: the farthest keyframe within this times the median depth (0: the "
          "nearest)");
  r->bind(s, "epipolar_partner_max_angle_deg", &max_angle_deg, 0.0, 180.0, "deg",
          "...whose optical axis is within this angle of the new keyframe's");
  r->bind(s, "epipolar_partners_mono", &partners_mono, 1, 100, "keyframes",
          "mono keyframes search against this many partners (the chosen one, then the nearest "
          "others within the angle)");
}

void MapperOptions::bind(OptionRegistry* r, const std::string& s) {
  ba_windows.bind(r, s);
  epipolar_partners.bind(r, s);
  epipolar.bind(r, s);
  matching.bind(r, s);
  refind.bind(r, s);
  cull.bind(r, s);
  keyframe_build.bind(r, s);
  ba.bind(r);
  loop_closure.bind(r);
  r->bind(s, "move_with_anchor", &move_with_anchor,
          "move a keyframe tracked against a map since moved by what its anchor keyframe has moved "
          "(false: every keyframe at its pose as it came)");
  // Ranges that only make sense together (a minimum above its maximum leaves nothing).
  r->requireBelow(s, "keyframe_min_depth_m", "keyframe_max_depth_m");
  r->requireBelow(s, "epipolar_min_depth_m", "epipolar_max_depth_m");
}

}  // namespace rgbdslam
