#pragma once
// Which map points the current frame may see, where, at which pyramid level, and how their
// source patches look from here (PTAM's tracker steps 2-3). Why: the patch search needs,
// for every visible point, its predicted pixel, the affine warp A_cur_src from its source
// keyframe and the search level chosen from that warp; the warped 8x8 patch is cached per
// point and re-warped only when the warp has changed noticeably (it changes slowly).
//
// Call order: the tracker keeps one PointSlot per map point (added / refreshed /
// removed as the replica changes); per frame, makeKeyframeViews(map, T_c_w) once, then
// projectPoint() for each slot, then ensurePatch() for each slot that will be searched.
//
// Frames and units: T_c_w maps world to the current camera; pixels at level 0 unless named
// *_level; A_cur_src maps a level-0 pixel offset in the source keyframe to a level-0 pixel
// offset in the current image (patch.h).
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/image/patch.h"
#include "rgbdslam/map/map.h"
#include "rgbdslam/tracking/depth_integrity.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

// Per-frame data of one keyframe: the rotation from its camera to the current camera, the
// third row of its T_c_w (for the point's depth in the source camera) and its camera's
// centre seen from the current camera (for the viewing-direction bound).
struct KeyframeView {
  bool valid = false;
  bool cold = false;  // the keyframe has no pyramid now (map_replica.h): its points have no slot
  Mat3 R_cur_src = Mat3::Identity();
  Eigen::RowVector3d src_z_row = Eigen::RowVector3d::Zero();  // z_src = row . p_w + t_z
  double src_z_offset = 0.0;
  Vec3 centre_c = Vec3::Zero();  // the keyframe camera's centre in the current camera's frame
};

// Indexed by keyframe id (ids are dense from 0).
void makeKeyframeViews(const Map& map, const SE3& T_c_w, std::vector<KeyframeView>* views);

struct PointSlot {
  MapPoint* point = nullptr;         // in the replica (stable until the point is removed)
  const Keyframe* source = nullptr;  // the point's source keyframe
  // d(normalised coordinates)/d(pixel) at the point's source pixel: the unprojection
  // Jacobian of the source camera (1/f on the diagonal without distortion).
  Eigen::Matrix2d d_m_d_uvsrc = Eigen::Matrix2d::Identity();
  // Patch cache: the warped patch and the warp it was made for, and its level (-1: none).
  // Out of line, made at the slot's first search and freed when the source keyframe goes
  // cold (MapReplica): most slots of a long flight's map are of cold keyframes, which never
  // search, so their 208 bytes a slot were memory held for nothing.
  struct PatchCache {
    Patch patch;
    Eigen::Matrix2d A = Eigen::Matrix2d::Zero();
  };
  std::unique_ptr<PatchCache> patch_cache;
  int patch_level = -1;
  const Patch& patch() const { return patch_cache->patch; }  // patch_level >= 0
  // Per frame, from projectPoint().
  Vec3 p_c = Vec3::Zero();
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  // predicted pixel, level 0
  Eigen::Matrix2d A_cur_src = Eigen::Matrix2d::Identity();
  int search_level = -1;
  // Per frame, from the search.
  bool searched = false;
  bool found = false;
  Eigen::Vector2d found_uv = Eigen::Vector2d::Zero();  // level 0
  int found_level = 0;
  // The depth integrity check (depth_integrity.h): this frame's verdict (the record of
  // accepted poses is the point's own, MapPoint::depth_record).
  DepthVerdict depth_verdict = DepthVerdict::kUnchecked;
};

// Fills the slot's point, source and unprojection Jacobian, and drops its patch cache.
// False if the source keyframe is not in the map.
bool initSlot(const Map& map, const PinholeCamera& camera, MapPoint* point, PointSlot* slot);

struct ProjectionOptions {
  int margin_px = 8;              // inside the image by this much [px]
  double min_depth_m = 0.05;      // in front of the camera by this much [m]
  // A point seen from a direction this far from its source keyframe's is not searched: its
  // patch, warped as if it faced the source camera, no longer looks like the point there
  // (0: any direction). ORB-SLAM bounds the angle to a point's mean viewing direction by
  // 60 deg; here the reference is the source keyframe, whose patch is searched for. Every
  // mode, mono too.
  double max_view_angle_deg = 60.0;  // [deg]

  void bind(OptionRegistry* registry, const std::string& section);  // margin_px, max_view_angle_deg
};

// Whether p_w lies in front of the camera at T_c_w and projects into the image (with margin):
// a point of a cold keyframe (no slot) waiting for the camera to come back.
bool inView(const PinholeCamera& camera, const SE3& T_c_w, const Vec3& p_w, const ProjectionOptions& options);
// False only when no point of the sphere can be inView: all of it nearer than min_depth_m
// or, for a camera without distortion, all of it beyond one side of the image's pyramid of
// view (with a distorted camera only the depth test applies: its projection of points far
// outside the image is not monotone). Conservative: true does not mean any point is in view.
bool sphereMayBeInView(const PinholeCamera& camera, const SE3& T_c_w, const Vec3& centre_w, double radius_m,
                       const ProjectionOptions& options);

// p_c, uv, A_cur_src and search_level of the slot at pose T_c_w. False when the point is
// behind the camera, outside the image (with margin), its source view is unknown or the
// warp is degenerate (chooseSearchLevel < 0).
bool projectPoint(const PinholeCamera& camera, const SE3& T_c_w,
                  const std::vector<KeyframeView>& views, const ProjectionOptions& options,
                  PointSlot* slot);

// Makes slot->patch the source patch warped by slot->A_cur_src at slot->search_level,
// reusing the cached one when the level is the same and no entry of A changed by more
// than 'tolerance'. False when the warp leaves the source image.
bool ensurePatch(PointSlot* slot, double tolerance);

}  // namespace rgbdslam

namespace rgbdslam {

// Patch acceptance and search of the tracker's stages (the radius is the stage's).
struct PointSearchOptions {
  int max_zmssd_per_pixel = 400;        // ZMSSD acceptance floor [grey^2 per patch pixel]
  // Acceptance relative to the template's own zero-mean energy E = sum (T - mean T)^2: a
  // match is accepted when ZMSSD < max(max_zmssd_per_pixel * kPatchArea, ratio * E). Why:
  // the ZMSSD of a correct match grows with the template's contrast (blur, resampling and
  // small appearance changes scale with the gradients), so an absolute threshold rejects
  // exactly the high-contrast patches that localise best. A flat image patch scores
  // ZMSSD = E, so ratio < 1 still rejects "no texture here". 0 disables (absolute only).
  double max_zmssd_energy_ratio = 0.5;
  // ...and in any case ZMSSD < max_zmssd_flat_ratio * E. Why: with template contrast s and
  // image noise sigma (per pixel), E = n (s^2 + sigma^2), a correct match scores about
  // 2 n sigma^2 and a textureless image patch n (s^2 + 2 sigma^2) >= E, whatever sigma is.
  // Without this cap the absolute floor accepts a weak template (E below the floor)
  // anywhere, e.g. on a plain corridor wall, and the pose stays at its prediction.
  // A ratio of 0.7 keeps templates whose contrast is at least ~1.5 times the noise
  // (2 sigma^2 / (s^2 + sigma^2) < 0.7). 0 disables (no cap).
  double max_zmssd_flat_ratio = 0.7;
  // When no FAST corner within the radius is accepted, also test every pixel within the
  // radius (PTAM searches corners only; under motion blur and on fine texture the true
  // position often is no FAST corner at this frame's threshold).
  bool dense_fallback = true;
  double patch_cache_tolerance = 0.05;  // see ensurePatch()
  SubpixelOptions subpixel;

  void bind(OptionRegistry* registry, const std::string& section);  // all but subpixel
};

// The ZMSSD below which the search accepts 'patch' (the options' three acceptance rules).
int patchAcceptance(const Patch& patch, const PointSearchOptions& options);

// Searches each slot's (warped) patch among the FAST corners of its search level within
// radius_px [px at the search level] of its predicted pixel (and, with dense_fallback, at
// every pixel in the radius when no corner is accepted) and refines the best match to
// sub-pixel. Sets searched (the patch could be made), found, found_uv (level 0) and
// found_level. Returns the number found.
int searchPoints(const std::vector<PointSlot*>& slots, const ImagePyramid& pyramid,
                 const std::vector<LevelCorners>& corners, int radius_px,
                 const PointSearchOptions& options);

}  // namespace rgbdslam
