#pragma once
// How map points are named, so that tracker and mapper name them alike without talking:
// keyframe k owns the ids [k * kPointsPerKeyframe, (k + 1) * kPointsPerKeyframe). The lower
// half are the provisional points the tracker creates from the keyframe's measured depth
// (the mapper adopts them with the keyframe), the upper half the points the mapper creates
// for k (epipolar search). Keyframes count from 0.
#include <cstdint>

namespace rgbdslam {

using KeyframeId = int64_t;
using PointId = int64_t;

constexpr int64_t kPointsPerKeyframe = int64_t{1} << 20;
constexpr int64_t kProvisionalPointsPerKeyframe = kPointsPerKeyframe / 2;

// The i-th provisional point of keyframe 'kf' (i < kProvisionalPointsPerKeyframe).
constexpr PointId provisionalPointId(KeyframeId kf, int64_t i) { return kf * kPointsPerKeyframe + i; }
// The i-th point the mapper creates for keyframe 'kf' (i < kPointsPerKeyframe / 2).
constexpr PointId mapperPointId(KeyframeId kf, int64_t i) {
  return kf * kPointsPerKeyframe + kProvisionalPointsPerKeyframe + i;
}
// The keyframe whose block holds the id.
constexpr KeyframeId keyframeOfPoint(PointId id) { return id / kPointsPerKeyframe; }
// Whether the id is one of keyframe kf's provisional points.
constexpr bool isProvisionalPointOf(PointId id, KeyframeId kf) {
  return id >= provisionalPointId(kf, 0) && id < mapperPointId(kf, 0);
}

}  // namespace rgbdslam
