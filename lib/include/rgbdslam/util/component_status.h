#pragma once
// A process's health report (carried by status_t): named counters and timings.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace rgbdslam {

struct ComponentStatus {
  int64_t utime = 0;  // time of the report [us]
  std::string component;
  std::string state;
  std::vector<std::pair<std::string, int64_t>> counters;
  std::vector<std::pair<std::string, double>> timings_ms;  // [ms]
};

}  // namespace rgbdslam
