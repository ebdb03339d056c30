#pragma once
// Map files: a map that outlives a run (docs/design.md, "Map files"). A later run loads it
// to localise in it (the tracker adds nothing) or to extend it (new keyframe ids continue
// after the loaded ones, so point ids, which derive from keyframe ids, cannot clash).
//
// Layout, version 1, all integers and doubles little-endian:
//   header (24 bytes): magic "RGBDSMAP" (8), version u32, payload length u64, CRC-32 (zlib)
//     of the payload u32
//   payload:
//     camera: name (str), width i32, height i32, fx fy cx cy k1 k2 p1 p2 k3 depth_factor f64
//     mode (str: mono | depth-init | depth-ba)
//     keyframes: count u32, then per keyframe in id order:
//       id i64, utime i64 [us], T_w_c as tx ty tz qx qy qz qw f64 [m, unit quaternion],
//       median_depth f64 [m], grey (bytes: PNG, lossless), has_depth u8, and if 1:
//       depth_scale f64 [raw units per metre] and depth (bytes: zlib of the 16-bit rows,
//       as keyframe_t carries it; 0 = no reading), then measurements: count u32, per
//       measurement point id i64, u v f64 [px, level 0], level i32, depth f64 [m, 0 = none]
//     points: count u32, then per point in id order: id i64, p_w xyz f64 [m],
//       source keyframe i64, source level i32, source uv f64 [px, level 0]
//   str = length u32 + bytes; bytes = length u32 + bytes.
// The decoder holds every count and length to the bytes left and to sane limits, checks
// every value (finite, unit quaternion, ids increasing, levels, pixels in the image, each
// measurement's point and each point's source keyframe present), and the images decode to
// the camera's size. Any failure is an error naming the file and the byte; no input crashes.
// Depth is stored in the camera's raw units: a keyframe's depth in metres (NaN = none)
// converts back to the raw readings it came from exactly (the mapper keeps readings inside
// the keyframe depth range only: the others were invalid already).
// Saving writes PATH.tmp-PID, syncs it and renames it over PATH: a crash mid-save leaves the
// old file (or none), never half a file under the name.
// Size: 0.25-0.41 MB per 640x480 keyframe (PNG and zlib depth), a map grows with its
// keyframes. Time: PNG/zlib coding, and on load each keyframe's pyramid and corners (figures
// in docs/design.md, "Map files").
#include <memory>
#include <string>
#include <vector>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/map/map.h"
#include "rgbdslam/map/map_types.h"
#include "rgbdslam/model/slam_mode.h"
#include "rgbdslam/util/expected.h"

namespace rgbdslam {

constexpr uint32_t kMapFileVersion = 1;

// A map as read from a file: what the mapper and the tracker start from.
struct LoadedMap {
  PinholeCamera camera;
  SlamMode mode = SlamMode::kDepthBa;
  // Id order. Each with its grey image, raw depth (or empty) and measurements; new_points
  // empty (the points are below) and map_id 0 (the loading run names its map).
  std::vector<KeyframeData> keyframes;
  std::vector<double> median_depths;  // per keyframe, as saved [m]
  std::vector<MapPointData> points;   // id order

  KeyframeId nextKeyframeId() const { return keyframes.empty() ? 0 : keyframes.back().id + 1; }
  // Keyframe i as saved (pose, median depth, measurements), its image structures rebuilt
  // (makeKeyframe). The map that takes it must take the points too.
  std::unique_ptr<Keyframe> buildKeyframe(size_t i, const KeyframeBuildOptions& options) const;
};

// The bytes of a map file for 'map' (every keyframe must hold its image: a mapper's map
// does; a tracker's cold keyframes do not, and are an error).
Expected<std::vector<uint8_t>> encodeMapFile(const Map& map, const PinholeCamera& camera, SlamMode mode);
// Decodes a map file's bytes; 'name' names the file in errors.
Expected<LoadedMap> decodeMapFile(const std::vector<uint8_t>& bytes, const std::string& name);

// encodeMapFile, written atomically to 'path' (temporary file, fsync, rename).
Status saveMap(const Map& map, const PinholeCamera& camera, SlamMode mode, const std::string& path);
// Reads and decodes 'path' and checks that it was made with 'expected' (size, intrinsics,
// distortion and depth factor; the name is only a label and may differ).
Expected<LoadedMap> loadMap(const std::string& path, const PinholeCamera& expected);

// Whether two cameras take the same images (all but the name), and a one-line description.
bool sameCamera(const PinholeCamera& a, const PinholeCamera& b);
std::string describeCamera(const PinholeCamera& camera);

}  // namespace rgbdslam
