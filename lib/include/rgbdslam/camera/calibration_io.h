#pragma once
// Loads a camera calibration from a YAML file (util/yaml_file.h; OpenCV's "%YAML:1.0" layout).
// Accepted layouts (see config/cameras/README.md):
//  - the project's own keys: name, image_width, image_height, fx, fy, cx, cy,
//    distortion (k1 k2 p1 p2 k3, optional, default zeros), depth_factor;
//  - ORB-SLAM style: Camera.fx, Camera.fy, Camera.cx, Camera.cy, Camera.k1 ... Camera.k3
//    (optional), Camera.width, Camera.height, DepthMapFactor.
// A missing or ill-typed required key, a value out of range, or a file whose top level is
// not a mapping is an error naming the key and the file.
#include <string>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/util/expected.h"

namespace rgbdslam {

// Largest image side a camera file may state: 8x a 1024 px camera; larger is a typo or a
// corrupt file (and 1e12 does not fit an int).
constexpr int kMaxCameraImageSide = 8192;  // [px]

Expected<PinholeCamera> loadCamera(const std::string& path);

}  // namespace rgbdslam
