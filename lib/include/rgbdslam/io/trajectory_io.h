#pragma once
// TUM trajectory format: one pose per line, "t tx ty tz qx qy qz qw", t in seconds,
// the pose T_w_c (camera to world); lines starting with '#' are comments.
#include <string>
#include <vector>

#include "rgbdslam/geometry/se3.h"
#include "rgbdslam/util/expected.h"

namespace rgbdslam {

struct TimedPose {
  double t = 0.0;  // [s]
  SE3 T_w_c;
};
using Trajectory = std::vector<TimedPose>;

// One line, with '\n', at full double precision for time and position (1e-9 s, 1e-9 m).
std::string formatTumLine(const TimedPose& pose);
// Parses one line; an error names what is wrong (the caller adds file and line number).
Expected<TimedPose> parseTumLine(const std::string& line);
// Reads a whole file; an error names the file and line. Skips comments and blank lines.
Expected<Trajectory> readTumTrajectory(const std::string& path);
Status writeTumTrajectory(const std::string& path, const Trajectory& trajectory);

}  // namespace rgbdslam
