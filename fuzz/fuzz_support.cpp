#include "fuzz_support.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>

namespace rgbdslam::fuzz {
namespace {

std::string& scratchDir() {
  static std::string dir;
  return dir;
}

void removeScratchDir() {
  std::error_code ignored;
  std::filesystem::remove_all(scratchDir(), ignored);
}

}  // namespace

std::string scratchPath(const std::string& name) {
  if (scratchDir().empty()) {
    // In memory where the machine has it: a file per execution on disk is slow.
    struct stat shm {};
    const std::string base = ::stat("/dev/shm", &shm) == 0 && S_ISDIR(shm.st_mode) ? "/dev/shm" : "/tmp";
    scratchDir() = base + "/rgbdslam-fuzz-" + std::to_string(::getpid());
    ::mkdir(scratchDir().c_str(), 0700);
    std::atexit(removeScratchDir);
  }
  return scratchDir() + "/" + name;
}

void writeFile(const std::string& path, const uint8_t* data, size_t size) {
  FILE* file = std::fopen(path.c_str(), "wb");
  if (!file || (size > 0 && std::fwrite(data, 1, size, file) != size) || std::fclose(file) != 0) {
    std::perror(path.c_str());
    std::abort();
  }
}

}  // namespace rgbdslam::fuzz
