#include "rgbdslam/io/trajectory_io.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace rgbdslam {

std::string formatTumLine(const TimedPose& pose) {
  const Vec3& t = pose.T_w_c.translation();
  const Eigen::Quaterniond& q = pose.T_w_c.rotation();
  // Sized by a first pass: a value of 1e200 prints 200 digits, and a line is never cut.
  const auto print = [&](char* out, size_t size) {
    return std::snprintf(out, size, "%.6f %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", pose.t, t.x(),
                         t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
  };
  std::string line(static_cast<size_t>(print(nullptr, 0)), '\0');
  print(line.data(), line.size() + 1);
  return line;
}

Expected<TimedPose> parseTumLine(const std::string& line) {
  std::istringstream in(line);
  double v[8];
  for (int i = 0; i < 8; ++i) {
    if (!(in >> v[i])) return Error{"expected 8 numbers 't tx ty tz qx qy qz qw'"};
    if (!std::isfinite(v[i])) return Error{"value " + std::to_string(i + 1) + " is not finite"};
  }
  std::string rest;
  if (in >> rest) return Error{"unexpected text after 8 numbers: '" + rest + "'"};
  const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
  if (std::abs(q.norm() - 1.0) > 1e-2) return Error{"quaternion is not of unit length"};
  return TimedPose{v[0], SE3(q, Vec3(v[1], v[2], v[3]))};
}

Expected<Trajectory> readTumTrajectory(const std::string& path) {
  std::ifstream file(path);
  if (!file) return Error{path + ": cannot open trajectory file"};
  Trajectory trajectory;
  std::string line;
  for (int number = 1; std::getline(file, line); ++number) {
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    auto pose = parseTumLine(line);
    if (!pose) return Error{path + ":" + std::to_string(number) + ": " + pose.error()};
    trajectory.push_back(*pose);
  }
  return trajectory;
}

Status writeTumTrajectory(const std::string& path, const Trajectory& trajectory) {
  std::ofstream file(path);
  if (!file) return Error{path + ": cannot write trajectory file"};
  file << "# timestamp tx ty tz qx qy qz qw (T_w_c)\n";
  for (const auto& pose : trajectory) file << formatTumLine(pose);
  if (!file) return Error{path + ": write failed"};
  return {};
}

}  // namespace rgbdslam
