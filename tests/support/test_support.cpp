#include "test_support.h"

#include <cstdlib>
#include <filesystem>
#include <stdexcept>

namespace rgbdslam::test {

bool isCi() {
  const char* ci = std::getenv("CI");
  return ci && std::string(ci) == "true";
}

std::string sourceDir() {
  const char* source = std::getenv("RGBDSLAM_SOURCE_DIR");
  return source ? source : RGBDSLAM_TEST_SOURCE_DIR;
}

std::string sharedDataPath(const std::string& name) {
  const char* shared = std::getenv("RGBDSLAM_SHARED_DIR");
  const std::string base = shared ? shared : RGBDSLAM_TEST_SHARED_DIR;
  const std::string path = base + "/data/" + name;
  return std::filesystem::exists(path) ? path : std::string();
}

TempDir::TempDir() {
  std::string pattern = (std::filesystem::temp_directory_path() / "rgbdslam-test-XXXXXX").string();
  if (!mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed");
  path_ = pattern;
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

}  // namespace rgbdslam::test
