#pragma once
// The three ways of using depth, to reproduce Table I of the paper:
//  mono       depth only for the first frame (map initialisation); new points by epipolar
//             search and triangulation; 2-D bundle adjustment.
//  depth-init points from measured depth where available (epipolar search elsewhere);
//             2-D bundle adjustment.
//  depth-ba   as depth-init, plus a 1-D depth residual per measurement in bundle adjustment
//             (the default).
#include <string>

#include "rgbdslam/util/expected.h"

namespace rgbdslam {

enum class SlamMode { kMono, kDepthInit, kDepthBa };

inline const char* slamModeName(SlamMode mode) {
  switch (mode) {
    case SlamMode::kMono: return "mono";
    case SlamMode::kDepthInit: return "depth-init";
    case SlamMode::kDepthBa: return "depth-ba";
  }
  return "?";
}

inline Expected<SlamMode> parseSlamMode(const std::string& text) {
  if (text == "mono") return SlamMode::kMono;
  if (text == "depth-init") return SlamMode::kDepthInit;
  if (text == "depth-ba") return SlamMode::kDepthBa;
  return Error{"unknown mode '" + text + "' (mono, depth-init, depth-ba)"};
}

// Whether points of keyframe 'keyframe_id' may be created from measured depth.
inline bool depthPointsAllowed(SlamMode mode, int64_t keyframe_id) {
  return mode != SlamMode::kMono || keyframe_id == 0;
}

// Whether the tracker may use the depth readings of the frames it tracks (depth residuals
// in the pose): not in mono, where depth serves only the map initialisation (the paper's
// "monocular visual SLAM": only the first RGB-D frame's depth, to fix the scale).
inline bool depthInTracking(SlamMode mode) { return mode != SlamMode::kMono; }

}  // namespace rgbdslam
