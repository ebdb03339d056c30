#pragma once
// Reading the project's YAML files (camera calibrations, the configuration) with libyaml, a
// small event parser that does bounded work per byte (and is fuzzed by OSS-Fuzz), into a
// tree of scalars, sequences and mappings. OpenCV's FileStorage parser, used before, could
// be made to hang by a 1.9 kB mangled configuration (fuzz_config) and let exceptions out.
// Limits: files up to 1 MiB, nesting 16 deep, 100 000 nodes; aliases (*name), more than one
// document, duplicate keys and keys that are not plain scalars are errors. OpenCV's header
// line "%YAML:1.0" (not a YAML directive) is read as a comment; tags (!!opencv-matrix) are
// ignored. Every error names the file and, where it has one, the line.
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "rgbdslam/util/expected.h"

namespace rgbdslam {

struct YamlNode {
  enum class Kind { kScalar, kSequence, kMapping };
  Kind kind = Kind::kScalar;
  std::string scalar;   // kScalar: the text as written (quotes removed)
  bool quoted = false;  // kScalar: in quotes, so a string even if it reads like a number
  int line = 0;         // where the node starts [1-based line]
  std::vector<YamlNode> items;                            // kSequence
  std::vector<std::pair<std::string, YamlNode>> entries;  // kMapping, in file order

  bool isScalar() const { return kind == Kind::kScalar; }
  bool isMapping() const { return kind == Kind::kMapping; }
  bool isSequence() const { return kind == Kind::kSequence; }
  // The entry 'key' of a mapping; nullptr if absent (or not a mapping).
  const YamlNode* find(const std::string& key) const;
  // An unquoted scalar whose whole text is a finite number (YAML's .inf and .nan are not).
  Expected<double> number() const;
};

// Parses YAML text; 'name' names it in errors (the file's path).
Expected<YamlNode> parseYaml(const std::string& text, const std::string& name);

// Reads 'path', checks that its top level is a mapping and calls read(root). 'what' names
// the kind of file ("camera", "configuration"), 'layout' shows the expected top level
// ("fx: ..., image_width: ...").
Status readYamlMapping(const std::string& path, const std::string& what, const std::string& layout,
                       const std::function<Status(const YamlNode& root)>& read);

}  // namespace rgbdslam
