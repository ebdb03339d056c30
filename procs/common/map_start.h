#pragma once
// The map a process starts from (--load-map FILE, docs/design.md "Map files"): rgbd-slam,
// rgbd-tracker and rgbd-mapper read it alike and refuse a map of another camera or mode.
#include <string>

#include "rgbdslam/map/map_file.h"
#include "rgbdslam/util/expected.h"

namespace rgbdslam {

// 'path' read and decoded, checked against this run's camera (map/map_file.h loadMap) and
// mode; errors start with "--load-map: ".
Expected<LoadedMap> loadStartMap(const std::string& path, const PinholeCamera& camera, SlamMode mode);

}  // namespace rgbdslam
