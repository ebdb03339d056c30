#include "rgbdslam/camera/calibration_io.h"

#include <cmath>
#include <filesystem>
#include <opencv2/core.hpp>

namespace rgbdslam {
namespace {

struct KeyReader {
  const cv::FileStorage& fs;
  const std::string& path;
  std::string error;

  bool has(const std::string& key) const { return !fs[key].empty() && !fs[key].isNone(); }

  // Reads a required number from the first of 'keys' present.
  double number(std::initializer_list<const char*> keys, bool required = true,
                double fallback = 0.0) {
    for (const char* key : keys) {
      if (!has(key)) continue;
      const cv::FileNode node = fs[key];
      if (!node.isReal() && !node.isInt()) {
        fail(std::string("key '") + key + "' is not a number");
        return fallback;
      }
      const double value = static_cast<double>(node);
      if (!std::isfinite(value)) fail(std::string("key '") + key + "' is not finite");
      return value;
    }
    if (required) fail(std::string("missing key '") + *keys.begin() + "'");
    return fallback;
  }

  void fail(const std::string& what) {
    if (error.empty()) error = path + ": " + what;
  }
};

void readDistortion(KeyReader& reader, PinholeCamera& camera) {
  if (reader.has("distortion")) {
    const cv::FileNode node = reader.fs["distortion"];
    std::vector<double> d;
    if (node.isSeq()) {
      for (const auto& item : node) {
        if (!item.isReal() && !item.isInt()) {
          reader.fail("key 'distortion' must be a list of numbers");
          return;
        }
        d.push_back(static_cast<double>(item));
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

}  // namespace

Expected<PinholeCamera> loadCamera(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) return Error{path + ": camera file not found"};
  cv::FileStorage fs;
  try {
    if (!fs.open(path, cv::FileStorage::READ)) return Error{path + ": cannot be read as YAML"};
  } catch (const cv::Exception& e) {
    return Error{path + ": not a valid OpenCV YAML file (" + e.msg + ")"};
  }
  KeyReader reader{fs, path, {}};
  PinholeCamera camera;
  if (reader.has("name") && fs["name"].isString()) {
    camera.name = static_cast<std::string>(fs["name"]);
  } else {
    camera.name = std::filesystem::path(path).stem().string();
  }
  camera.fx = reader.number({"fx", "Camera.fx"});
  camera.fy = reader.number({"fy", "Camera.fy"});
  camera.cx = reader.number({"cx", "Camera.cx"});
  camera.cy = reader.number({"cy", "Camera.cy"});
  camera.width = static_cast<int>(reader.number({"image_width", "Camera.width"}));
  camera.height = static_cast<int>(reader.number({"image_height", "Camera.height"}));
  camera.depth_factor = reader.number({"depth_factor", "DepthMapFactor"});
  readDistortion(reader, camera);
  if (!reader.error.empty()) return Error{reader.error};
  if (camera.fx <= 0 || camera.fy <= 0) return Error{path + ": fx and fy must be positive"};
  if (camera.width <= 0 || camera.height <= 0) {
    return Error{path + ": image size must be positive"};
  }
  if (camera.depth_factor <= 0) return Error{path + ": depth factor must be positive"};
  return camera;
}

}  // namespace rgbdslam
