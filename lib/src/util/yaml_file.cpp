#include "rgbdslam/util/yaml_file.h"

#include <filesystem>
#include <opencv2/core.hpp>

namespace rgbdslam {

Status readYamlMapping(const std::string& path, const std::string& what, const std::string& layout,
                       const std::function<Status(const cv::FileNode& root)>& read) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) return Error{path + ": " + what + " file not found"};
  try {
    cv::FileStorage fs;
    if (!fs.open(path, cv::FileStorage::READ)) return Error{path + ": cannot be read as YAML"};
    if (!fs.root().isMap()) {
      return Error{path + ": the top level must be a mapping (" + layout + "), not a list or a value"};
    }
    return read(fs.root());
  } catch (const cv::Exception& e) {
    return Error{path + ": not a valid " + what + " file (" + e.msg + ")"};
  } catch (const std::exception& e) {  // OpenCV's parser also lets std::length_error through
    return Error{path + ": not a valid " + what + " file (" + e.what() + ")"};
  }
}

}  // namespace rgbdslam
