#pragma once
// New map points by epipolar search (PTAM's AddSomeMapPoints; paper III-C): for corners of
// a new keyframe that have no depth reading (every corner in mono mode), search the 8x8
// patch along the epipolar segment of the plausible depth range in another keyframe (the
// nearest one) among that keyframe's FAST corners of the same pyramid level, (optionally)
// check that the best ZMSSD match searched back finds the corner (cross_check), refine it to
// sub-pixel accuracy and triangulate the two rays (midpoint).
//
// Call order: epipolarSearch(new_kf, nearest_kf, ...) after the new keyframe's own
// measurements are in it (corners near them are skipped); the caller adds the returned
// points and both measurements (depth 0: the caller fills depth where it is allowed).
// Frames and units: T_w_c camera to world; pixels at level 0 unless named *_level; metres.
#include <optional>
#include <vector>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/map/map.h"
#include "rgbdslam/mapping/data_association.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct EpipolarOptions {
  double min_depth_m = 0.3;           // search range along the ray of the new keyframe [m]
  double max_depth_m = 8.0;           // [m]
  int max_points = 300;               // corners tried (strongest Shi-Tomasi first)
  double min_shi_tomasi = 30.0;       // weaker corners are not tried [(grey/px)^2]
  // A keyframe that measures fewer than weak_until_points points (a weakly textured view:
  // corridor walls, where the strong corners are far away and too close to the epipole to
  // triangulate in forward motion) also tries weaker corners, down to weak_min_shi_tomasi,
  // after the strong ones and with a budget of max_points of their own, until it measures
  // weak_until_points (0: never). The mapper uses it only where every point must come from
  // epipolar search (mono): in the depth modes the points from depth took those corners.
  double weak_min_shi_tomasi = 10.0;  // [(grey/px)^2]
  int weak_until_points = 100;        // [points]
  double min_separation_px = 8.0;     // from measured points and each other, level 0 [px]
  double line_tolerance_px = 1.5;     // corner distance from the segment [level px]
  double distinctiveness = 0.8;       // best ZMSSD < this * second best (> 2 px away) [-]
  // The match searched back along its own epipolar segment must find the corner it came
  // from (within 2 px at the level): stereo's left-right consistency, against chance matches
  // on the near end of a segment whose true match lies beyond it (a surface beyond the
  // range: "near ghosts"). It costs 1.5-3.6 times the search time (bench_epipolar), on the
  // ground station's mapper. On since session 26: with the tracker's motion prior no whole
  // run measured is clearly worse with it, the flight's worst world of 20 (first 720 frames)
  // went 7.3 -> 5.5 mm and the rest moved within the spread between worlds and seeds
  // (docs/open_work.md, session 26); before the prior, runs tipped on the points it refuses
  // (session 23). The mapper applies it in the depth modes only (mono
  // searches every corner, and the paper's Table I was measured without it).
  bool cross_check = true;
  double min_parallax_deg = 1.0;      // smaller angles between the rays are rejected [deg]
  double max_reprojection_px = 2.0;   // triangulated point's error in either view [level px]
  // Only corners without a depth reading (the depth modes); set by the mapper per keyframe
  // from the mode, not configured.
  bool skip_corners_with_depth = true;

  void bind(OptionRegistry* registry, const std::string& section);  // as epipolar_*
};

struct EpipolarPoint {
  MapPoint point;          // id, p_w, source = the new keyframe, its level and pixel
  Measurement in_keyframe; // in the new keyframe (depth 0)
  Measurement in_other;    // in the other keyframe (depth 0)
};

struct EpipolarStats {
  int tried = 0, no_candidate = 0, no_match = 0, ambiguous = 0, cross_check_failed = 0,
      subpixel_failed = 0, bad_triangulation = 0, created = 0;
};

// Points ids are first_id + i; 'matching' accepts the best match. 'stats' (optional)
// receives the counts per outcome.
std::vector<EpipolarPoint> epipolarSearch(const Keyframe& keyframe, const Keyframe& other,
                                          const PinholeCamera& camera, const EpipolarOptions& options,
                                          const PatchMatchOptions& matching, PointId first_id,
                                          EpipolarStats* stats = nullptr);

// Midpoint of the shortest segment between two rays (origins o_a, o_b and unit directions
// d_a, d_b in the world). nullopt when the rays are (nearly) parallel or the point lies
// behind either origin.
std::optional<Vec3> triangulateMidpoint(const Vec3& o_a, const Vec3& d_a, const Vec3& o_b,
                                        const Vec3& d_b);

}  // namespace rgbdslam
