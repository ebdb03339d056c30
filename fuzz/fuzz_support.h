#pragma once
// Helpers shared by the libFuzzer targets: a scratch folder per fuzzing process for the
// parsers that read files (camera, configuration, TUM lists, journal).
#include <cstddef>
#include <cstdint>
#include <string>

namespace rgbdslam::fuzz {

// /dev/shm/rgbdslam-fuzz-PID/NAME (/tmp without /dev/shm); the folder is made once per
// process and removed when it exits normally.
std::string scratchPath(const std::string& name);
// Writes size bytes to path (truncating); aborts when the scratch file cannot be written,
// since every later run would test nothing.
void writeFile(const std::string& path, const uint8_t* data, size_t size);

}  // namespace rgbdslam::fuzz
