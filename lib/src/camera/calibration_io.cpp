#include "rgbdslam/camera/calibration_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "rgbdslam/util/yaml_file.h"

namespace rgbdslam {
namespace {

struct KeyReader {
  const YamlNode& fs;  // the file's top level (a mapping)
  const std::string& path;
  std::string error;

  bool has(const std::string& key) const {
    const YamlNode* node = fs.find(key);
    return node && !(node->isScalar() && !node->quoted && (node->scalar.empty() || node->scalar == "~" || node->scalar == "null"));
  }

  // Reads a required number from the first of 'keys' present.
  double number(std::initializer_list<const char*> keys, bool required = true,
                double fallback = 0.0) {
    for (const char* key : keys) {
      if (!has(key)) continue;
      const auto value = fs.find(key)->number();
      if (!value) {
        fail(std::string("key '") + key + "' " + value.error());
        return fallback;
      }
      return *value;
    }
    if (required) fail(std::string("missing key '") + *keys.begin() + "'");
    return fallback;
  }

  // Reads a required whole number within [min, max] from the first of 'keys' present.
  int integer(std::initializer_list<const char*> keys, int min, int max) {
    const double value = number(keys, true, 0.0);
    if (!error.empty()) return 0;
    if (value != std::floor(value) || value < min || value > max) {
      const std::string key = *std::find_if(keys.begin(), keys.end(), [&](const char* k) { return has(k); });
      fail("key '" + key + "' is " + text(value) + ", must be a whole number in [" +
           std::to_string(min) + ", " + std::to_string(max) + "]");
      return 0;
    }
    return static_cast<int>(value);
  }

  static std::string text(double value) {
    char out[32];
    std::snprintf(out, sizeof out, "%g", value);
    return out;
  }

  void fail(const std::string& what) {
    if (error.empty()) error = path + ": " + what;
  }
};

void readDistortion(KeyReader& reader, PinholeCamera& camera) {
  if (reader.has("distortion")) {
    const YamlNode& node = *reader.fs.find("distortion");
    std::vector<double> d;
    if (node.isSequence()) {
      for (const YamlNode& item : node.items) {
        const auto value = item.number();
        if (!value) {
          reader.fail("key 'distortion' must be a list of numbers");
          return;
        }
        d.push_back(*value);
      }
    }
    if (d.size() != 4 && d.size() != 5) {
      reader.fail("key 'distortion' must list 4 or 5 numbers (k1 k2 p1 p2 [k3])");
      return;
    }
    d.resize(5, 0.0);
    camera.k1 = d[0], camera.k2 = d[1], camera.p1 = d[2], camera.p2 = d[3], camera.k3 = d[4];
    return;
  }
  camera.k1 = reader.number({"Camera.k1"}, false);
  camera.k2 = reader.number({"Camera.k2"}, false);
  camera.p1 = reader.number({"Camera.p1"}, false);
  camera.p2 = reader.number({"Camera.p2"}, false);
  camera.k3 = reader.number({"Camera.k3"}, false);
}

Expected<PinholeCamera> readCamera(const YamlNode& fs, const std::string& path) {
  KeyReader reader{fs, path, {}};
  PinholeCamera camera;
  if (reader.has("name") && fs.find("name")->isScalar()) {
    camera.name = fs.find("name")->scalar;
  } else {
    camera.name = std::filesystem::path(path).stem().string();
  }
  camera.fx = reader.number({"fx", "Camera.fx"});
  camera.fy = reader.number({"fy", "Camera.fy"});
  camera.cx = reader.number({"cx", "Camera.cx"});
  camera.cy = reader.number({"cy", "Camera.cy"});
  camera.width = reader.integer({"image_width", "Camera.width"}, 1, kMaxCameraImageSide);
  camera.height = reader.integer({"image_height", "Camera.height"}, 1, kMaxCameraImageSide);
  camera.depth_factor = reader.number({"depth_factor", "DepthMapFactor"});
  readDistortion(reader, camera);
  if (!reader.error.empty()) return Error{reader.error};
  if (camera.fx <= 0 || camera.fy <= 0) {
    return Error{path + ": fx and fy must be positive, got " + KeyReader::text(camera.fx) + " and " + KeyReader::text(camera.fy)};
  }
  if (camera.depth_factor <= 0) {
    return Error{path + ": depth factor must be positive, got " + KeyReader::text(camera.depth_factor)};
  }
  return camera;
}

}  // namespace

Expected<PinholeCamera> loadCamera(const std::string& path) {
  std::optional<Expected<PinholeCamera>> camera;
  const Status read = readYamlMapping(path, "camera", "keys such as fx: ..., image_width: ...",
                                      [&](const YamlNode& root) {
                                        camera = readCamera(root, path);
                                        return *camera ? Status{} : Status(Error{camera->error()});
                                      });
  if (!read) return Error{read.error()};
  return *camera;
}

}  // namespace rgbdslam
