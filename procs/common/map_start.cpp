#include "common/map_start.h"

namespace rgbdslam {

Expected<LoadedMap> loadStartMap(const std::string& path, const PinholeCamera& camera, SlamMode mode) {
  auto loaded = loadMap(path, camera);
  if (!loaded) return Error{"--load-map: " + loaded.error()};
  if (loaded->mode != mode) {
    return Error{"--load-map: " + path + " was made in mode " + slamModeName(loaded->mode) + "; this run's mode is " +
                 slamModeName(mode) + " (--mode or slam.mode)"};
  }
  return loaded;
}

}  // namespace rgbdslam
