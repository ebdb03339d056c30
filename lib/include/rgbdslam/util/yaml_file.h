#pragma once
// Reading an OpenCV FileStorage YAML file whose top level must be a mapping (camera files,
// the SLAM configuration). OpenCV throws cv::Exception for a malformed file and for a key
// lookup on a node that is not a mapping (a top level that is a list aborted every process),
// and lets std::length_error out of its parser (found by fuzz_config: 16 bytes of YAML);
// here all become errors naming the file.
#include <functional>
#include <string>

#include "rgbdslam/util/expected.h"

namespace cv {
class FileNode;
}

namespace rgbdslam {

// Opens 'path', checks that its top level is a mapping and calls read(root). 'what' names
// the kind of file ("camera", "configuration"), 'layout' shows the expected top level
// ("fx: ..., image_width: ...").
Status readYamlMapping(const std::string& path, const std::string& what, const std::string& layout,
                       const std::function<Status(const cv::FileNode& root)>& read);

}  // namespace rgbdslam
