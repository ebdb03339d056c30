#pragma once
// The shared process skeleton: signal handling that only sets an atomic flag, the host clock,
// and opening LCM with a clear error. Every main has the same shape:
//   parse arguments -> load and validate configuration (print it) -> build the algorithm ->
//   subscribe handlers -> while (!stop) lcm.handleTimeout(...).
#include <atomic>
#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>

#include "rgbdslam/util/expected.h"

namespace rgbdslam {

// Installs SIGINT/SIGTERM handlers that set the returned flag (and nothing else).
std::atomic<bool>& installStopHandlers();

// Host clock, microseconds since the epoch.
int64_t utimeNow();

// Opens LCM at 'url'; an error (not an abort) if the URL is bad or the network unusable.
Expected<std::unique_ptr<lcm::LCM>> openLcm(const std::string& url);

// Prints "program: error: message" to stderr and returns the exit status for bad usage (2).
int usageError(const std::string& program, const std::string& message);

}  // namespace rgbdslam
