#pragma once
// The protocol's limits: every count, size and value a message may claim, with the reason
// for each bound. The wire check (wire_check.h) holds counts and lengths to these before
// anything is decoded or allocated; the conversions (lcm_conversions.h) hold decoded values
// to them. A message beyond a limit is malformed or hostile: it is rejected with an error
// naming the field, never clamped.
#include <cstdint>

#include "rgbdslam/camera/calibration_io.h"
#include "rgbdslam/image/pyramid.h"
#include "rgbdslam/map/map_types.h"

namespace rgbdslam::limits {

// Images: no larger than a camera file may state (8192 px a side, 8x a 1024 px camera);
// larger is a corrupt header.
constexpr int kMaxImageSide = rgbdslam::kMaxCameraImageSide;  // [px]
// Encoded image bytes (colour, grey, depth): raw BGR at the largest side, the largest any
// encoding needs. Also below liblcm's 32-bit size arithmetic (2^31 bytes).
constexpr int64_t kMaxImageBytes = int64_t{kMaxImageSide} * kMaxImageSide * 3;  // [bytes]

// Per keyframe: measurements and new points. A 640x480 keyframe has about 10^3; one per
// pixel of a 1 Mpixel image is far beyond what the tracker (fine_max_points <= 10^5) makes.
constexpr int32_t kMaxKeyframePoints = 1 << 20;
// Per map message: keyframes (poses, removed ids). One keyframe a frame at 30 Hz for
// 9 hours; the full 110 m corridor has a few hundred.
constexpr int32_t kMaxMapKeyframes = 1 << 20;
// Per map message: new, moved and removed points. 2^22 (37 bytes each: 155 MB) is 16x the
// points of the full corridor's map.
constexpr int32_t kMaxMapPoints = 1 << 22;
// Status reports: named counters and timings, and the length of any name or free text.
constexpr int32_t kMaxStatusEntries = 1024;
constexpr int32_t kMaxStringBytes = 4096;  // [bytes] including the terminating NUL

// World: positions (camera centres, points) within 10 km of the map's origin; beyond it a
// float point position has cm resolution and the bundle adjuster's numbers lose meaning
// (1e155 m aborted Ceres). A MAV's indoor map spans tens of metres.
constexpr double kMaxWorldCoordinateM = kWorldBoundM;  // [m] per axis (map_types.h)
// Measured depths: no RGB-D sensor reads beyond 100 m (Kinect: 10 m); the options'
// max_depth_m is bounded alike.
constexpr double kMaxDepthM = 100.0;  // [m]
// Depth units per metre: TUM 5000, OpenNI 1000; 10^6 is micrometre units.
constexpr double kMaxDepthScale = 1e6;
// A unit quaternion's norm may differ from 1 by this (float round trips, renormalisation).
constexpr double kQuaternionNormTolerance = 1e-3;
// Pyramid levels: measurements and points index the keyframe's pyramid.
constexpr int kMaxLevels = rgbdslam::kMaxLevels;  // levels 0 .. kMaxLevels - 1

}  // namespace rgbdslam::limits
