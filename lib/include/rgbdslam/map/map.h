#pragma once
// The keyframe map of PTAM: keyframes (pose, image pyramid, FAST corners, depth, small
// blurry image, the measurements made in them) and map points (world position and the
// patch that describes them: source keyframe, level and pixel).
//
// Invariant: a keyframe measures a point exactly when the keyframe is among the point's
// observers; measurements change only through Map (Keyframe::measurements() is read-only).
// Ownership: the mapper owns the authoritative map; the tracker keeps a replica that it
// extends with provisional keyframes and points and updates from MapUpdate messages. Both
// are instances of this class; it has no locks (one thread owns each instance).
// Frames: T_w_c maps camera to world; p_w world coordinates [m]; pixels at level 0.
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <unordered_map>
#include <vector>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/image/corners.h"
#include "rgbdslam/image/pyramid.h"
#include "rgbdslam/image/small_blurry_image.h"
#include "rgbdslam/map/depth_record.h"
#include "rgbdslam/map/keyframe_depth.h"
#include "rgbdslam/map/map_types.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

class Map;
struct KeyframeBuildOptions;

struct Keyframe {
  KeyframeId id = -1;
  int64_t utime = 0;        // acquisition time [us]
  SE3 T_w_c;
  KeyframeDepth depth;      // raw readings, read in metres (keyframe_depth.h), or empty
  ImagePyramid pyramid;     // grey, kMaxLevels levels
  std::vector<LevelCorners> corners;  // FAST corners per level
  SmallBlurryImage sbi;     // for relocalisation
  double median_depth = 2.0;  // median depth of the points it measures [m]
  // The part of the map it belongs to (the mapper's; mapper.h, "Parts"): the id of the
  // keyframe that started the part (0 for the map's start), which stays its name after that
  // keyframe is culled. A part's keyframes and points are tied to the other parts' only by
  // the loop closer, which merges two parts when it joins them.
  KeyframeId part = 0;
  // The tracker's local map (tracking/map_replica.h): a keyframe away from the camera is
  // 'cold': no pyramid, its level-0 image kept as JPEG here, rebuilt when the camera comes
  // back (empty while the tracker's keyframe store holds it). The mapper's keyframes are
  // never cold.
  std::vector<uint8_t> cold_grey;
  bool cold() const { return pyramid.levels.empty(); }

  SE3 T_c_w() const { return T_w_c.inverse(); }
  const cv::Mat& grey() const { return pyramid.levels[0]; }
  // Frees what only the mapper reads after the keyframe's points are made (the depth, 2 bytes
  // a pixel or fewer, the corners and the measurements): the tracker's replica keeps the
  // pyramid (the points' patches) and the small blurry image (relocalisation). Call it
  // before the keyframe joins a Map (the Map indexes the measurements when it is added).
  void releaseMappingData();
  // Depth [m] at a level-0 pixel (nearest pixel); nullopt when there is no valid reading.
  std::optional<double> depthAt(const Eigen::Vector2d& uv) const;
  // The points seen in this keyframe. Changed only through the Map that holds the
  // keyframe, which keeps its index of observers in step.
  const std::unordered_map<PointId, Measurement>& measurements() const { return measurements_; }

 private:
  friend class Map;
  friend std::unique_ptr<Keyframe> makeKeyframe(const KeyframeData&, const KeyframeBuildOptions&);
  std::unordered_map<PointId, Measurement> measurements_;
};

struct MapPoint {
  PointId id = -1;
  Vec3 p_w = Vec3::Zero();
  KeyframeId source_keyframe = -1;  // keyframe whose image holds the point's patch
  int source_level = 0;             // pyramid level of the patch
  Eigen::Vector2d source_uv = Eigen::Vector2d::Zero();  // patch centre, level 0 [px]
  int times_projected = 0;  // tracker: frames in which it was predicted visible and searched
  int times_found = 0;      // tracker: frames in which it was found
  DepthRecord depth_record;  // tracker: the depth integrity check at accepted poses

  MapPoint() = default;
  // A point as the messages describe it (tracker statistics zero).
  explicit MapPoint(const MapPointData& d)
      : id(d.id), p_w(d.p_w), source_keyframe(d.source_keyframe), source_level(d.level),
        source_uv(d.uv) {}
  MapPointData data() const { return {id, p_w, source_keyframe, source_uv, source_level}; }
};

// Options for building a keyframe's image structures.
struct KeyframeBuildOptions {
  CornerOptions corners;
  double min_depth_m = 0.3;  // readings nearer than this are treated as invalid [m]
  double max_depth_m = 8.0;  // readings farther than this are treated as invalid [m]

  void bind(OptionRegistry* registry, const std::string& section);  // the depth range
};

// Builds pyramid, corners, SBI and depth (keyframe_depth.h) from a keyframe message's content, with its
// measurements (the Map indexes them when the keyframe is added). data.depth must not be
// written afterwards: the keyframe's depth may share its buffer.
std::unique_ptr<Keyframe> makeKeyframe(const KeyframeData& data, const KeyframeBuildOptions& options);
// Converts raw depth to metres with NaN for invalid readings (0, out of range).
cv::Mat depthToMetres(const cv::Mat& raw, double depth_scale, double min_m, double max_m);

class Map {
 public:
  Keyframe* addKeyframe(std::unique_ptr<Keyframe> keyframe);
  Keyframe* keyframe(KeyframeId id);
  const Keyframe* keyframe(KeyframeId id) const;
  bool hasKeyframe(KeyframeId id) const { return keyframes_.count(id) > 0; }
  const std::map<KeyframeId, std::unique_ptr<Keyframe>>& keyframes() const { return keyframes_; }
  // Removes the keyframe and every measurement made in it, and remembers its id. Points
  // whose source it is keep a dangling source: the caller re-describes them from another
  // keyframe or removes them first (map_maintenance.h).
  void removeKeyframe(KeyframeId id);
  // Every keyframe removed so far (snapshots list them: map_diff.h).
  const std::set<KeyframeId>& removedKeyframes() const { return removed_keyframes_; }
  size_t numKeyframes() const { return keyframes_.size(); }

  // Adds or replaces a point (keeps the tracker's statistics and depth record when replacing).
  MapPoint* addPoint(const MapPoint& point);
  MapPoint* point(PointId id);
  const MapPoint* point(PointId id) const;
  // Removes the point and every measurement of it.
  void removePoint(PointId id);
  const std::unordered_map<PointId, MapPoint>& points() const { return points_; }
  size_t numPoints() const { return points_.size(); }

  // Adds (or replaces) a measurement of an existing point in an existing keyframe.
  void addMeasurement(KeyframeId keyframe_id, const Measurement& measurement);
  // Removes one measurement; the point stays, with its other measurements.
  void removeMeasurement(KeyframeId keyframe_id, PointId point_id);
  // Sets the depth reading of an existing measurement (0: none, e.g. a depth outlier).
  void setMeasurementDepth(KeyframeId keyframe_id, PointId point_id, double depth);
  // Keyframes that measure the point, in the order their measurements were added.
  std::vector<KeyframeId> observers(PointId id) const;

  // The n keyframes nearest to a pose: by camera-centre distance plus a penalty for viewing
  // direction (metres per radian, PTAM-like), nearest first.
  std::vector<KeyframeId> nearestKeyframes(const SE3& T_w_c, size_t n,
                                           double metres_per_radian = 0.5) const;
  // The same among the keyframes of one part (Keyframe::part).
  std::vector<KeyframeId> nearestKeyframesInPart(const SE3& T_w_c, size_t n, KeyframeId part) const;
  // The part of a point: its source keyframe's (-1 when that keyframe is not in the map).
  KeyframeId partOfPoint(const MapPoint& point) const;
  // The keyframes whose camera centre is within 'radius_m' of T_w_c's, in id order.
  std::vector<KeyframeId> keyframesWithin(const SE3& T_w_c, double radius_m) const;

 private:
  std::map<KeyframeId, std::unique_ptr<Keyframe>> keyframes_;
  std::unordered_map<PointId, MapPoint> points_;
  std::unordered_map<PointId, std::vector<KeyframeId>> observers_;
  std::set<KeyframeId> removed_keyframes_;
};

}  // namespace rgbdslam
