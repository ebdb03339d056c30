#pragma once
// Helpers shared by the tests: where the shared data lives, and a temporary folder.
#include <string>

namespace rgbdslam::test {

// Path of ../shared/data/NAME. If it is missing: in CI (CI=true) the calling test fails,
// elsewhere it is skipped with a message. Use through RGBDSLAM_REQUIRE_SHARED_DATA.
std::string sharedDataPath(const std::string& name);
bool isCi();
// The repository's root (for config/ files).
std::string sourceDir();
// A new empty folder under the system temp dir, removed by the destructor.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }
  std::string file(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

}  // namespace rgbdslam::test

// Sets 'var' to the data path, or fails (CI) / skips (elsewhere) the test when it is missing.
#define RGBDSLAM_REQUIRE_SHARED_DATA(var, name)                                         \
  const std::string var = ::rgbdslam::test::sharedDataPath(name);                       \
  if (var.empty()) {                                                                    \
    if (::rgbdslam::test::isCi()) FAIL() << "../shared/data/" << name << " is missing"; \
    GTEST_SKIP() << "../shared/data/" << name << " is missing; skipping";               \
  }
