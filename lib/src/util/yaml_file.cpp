#include "rgbdslam/util/yaml_file.h"

#include <yaml.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>

namespace rgbdslam {
namespace {

constexpr size_t kMaxFileBytes = 1 << 20;
constexpr int kMaxDepth = 16;
constexpr long kMaxNodes = 100000;

// libyaml's event stream turned into a tree, with the limits above.
class TreeBuilder {
 public:
  TreeBuilder(const std::string& text, std::string name) : name_(std::move(name)) {
    yaml_parser_initialize(&parser_);
    yaml_parser_set_input_string(&parser_, reinterpret_cast<const unsigned char*>(text.data()), text.size());
  }
  ~TreeBuilder() { yaml_parser_delete(&parser_); }
  TreeBuilder(const TreeBuilder&) = delete;
  TreeBuilder& operator=(const TreeBuilder&) = delete;

  Expected<YamlNode> build() {
    if (Status s = expect(YAML_STREAM_START_EVENT); !s) return Error{s.error()};
    auto event = next();
    if (!event) return Error{event.error()};
    if (event->type == YAML_STREAM_END_EVENT) return Error{name_ + ": is empty"};
    if (event->type != YAML_DOCUMENT_START_EVENT) return Error{name_ + ": no YAML document"};
    auto root = node(0);
    if (!root) return root;
    if (Status s = expect(YAML_DOCUMENT_END_EVENT); !s) return Error{s.error()};
    event = next();
    if (!event) return Error{event.error()};
    if (event->type != YAML_STREAM_END_EVENT) return Error{at(event->line) + "holds more than one document"};
    return root;
  }

 private:
  struct Event {
    yaml_event_type_t type;
    std::string scalar;
    bool quoted = false;
    int line = 0;
  };

  Expected<Event> next() {
    yaml_event_t event;
    if (!yaml_parser_parse(&parser_, &event)) {
      const std::string problem = parser_.problem ? parser_.problem : "not valid YAML";
      return Error{at(static_cast<int>(parser_.problem_mark.line) + 1) + problem};
    }
    Event out{event.type, {}, false, static_cast<int>(event.start_mark.line) + 1};
    if (event.type == YAML_SCALAR_EVENT) {
      out.scalar.assign(reinterpret_cast<const char*>(event.data.scalar.value), event.data.scalar.length);
      out.quoted = event.data.scalar.style == YAML_SINGLE_QUOTED_SCALAR_STYLE ||
                   event.data.scalar.style == YAML_DOUBLE_QUOTED_SCALAR_STYLE;
    }
    yaml_event_delete(&event);
    return out;
  }

  Status expect(yaml_event_type_t type) {
    auto event = next();
    if (!event) return Error{event.error()};
    if (event->type != type) return Error{at(event->line) + "unexpected content"};
    return Status{};
  }

  // The node whose first event comes next.
  Expected<YamlNode> node(int depth) {
    auto event = next();
    if (!event) return Error{event.error()};
    return nodeFrom(*event, depth);
  }

  Expected<YamlNode> nodeFrom(const Event& event, int depth) {
    if (++nodes_ > kMaxNodes) return Error{at(event.line) + "more than " + std::to_string(kMaxNodes) + " nodes"};
    if (depth > kMaxDepth) return Error{at(event.line) + "nested more than " + std::to_string(kMaxDepth) + " deep"};
    YamlNode out;
    out.line = event.line;
    switch (event.type) {
      case YAML_SCALAR_EVENT:
        out.scalar = event.scalar;
        out.quoted = event.quoted;
        return out;
      case YAML_ALIAS_EVENT:
        return Error{at(event.line) + "aliases (*name) are not supported"};
      case YAML_SEQUENCE_START_EVENT:
        out.kind = YamlNode::Kind::kSequence;
        for (;;) {
          auto item = next();
          if (!item) return Error{item.error()};
          if (item->type == YAML_SEQUENCE_END_EVENT) return out;
          auto child = nodeFrom(*item, depth + 1);
          if (!child) return child;
          out.items.push_back(std::move(*child));
        }
      case YAML_MAPPING_START_EVENT:
        out.kind = YamlNode::Kind::kMapping;
        for (;;) {
          auto key = next();
          if (!key) return Error{key.error()};
          if (key->type == YAML_MAPPING_END_EVENT) return out;
          if (key->type != YAML_SCALAR_EVENT) return Error{at(key->line) + "a key must be a plain name"};
          if (out.find(key->scalar)) return Error{at(key->line) + "key '" + key->scalar + "' appears twice"};
          auto value = node(depth + 1);
          if (!value) return value;
          out.entries.emplace_back(key->scalar, std::move(*value));
        }
      default:
        return Error{at(event.line) + "unexpected content"};
    }
  }

  std::string at(int line) const { return name_ + ":" + std::to_string(line) + ": "; }

  yaml_parser_t parser_;
  std::string name_;
  long nodes_ = 0;
};

}  // namespace

const YamlNode* YamlNode::find(const std::string& key) const {
  for (const auto& [name, value] : entries) {
    if (name == key) return &value;
  }
  return nullptr;
}

Expected<double> YamlNode::number() const {
  if (kind != Kind::kScalar || quoted || scalar.empty()) return Error{"is not a number"};
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(scalar.c_str(), &end);
  if (*end != '\0' || errno != 0 || !std::isfinite(v)) return Error{"is not a finite number"};
  return v;
}

Expected<YamlNode> parseYaml(const std::string& text, const std::string& name) {
  std::string input = text;
  // OpenCV writes "%YAML:1.0" (a directive YAML does not know): a comment of the same length.
  if (input.rfind("%YAML:", 0) == 0) input[0] = '#';
  return TreeBuilder(input, name).build();
}

Status readYamlMapping(const std::string& path, const std::string& what, const std::string& layout,
                       const std::function<Status(const YamlNode& root)>& read) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) return Error{path + ": " + what + " file not found"};
  const auto size = std::filesystem::file_size(path, error);
  if (error) return Error{path + ": cannot be read: " + error.message()};
  if (size > kMaxFileBytes) {
    return Error{path + ": " + std::to_string(size) + " bytes, more than a " + what + " file holds (1 MiB)"};
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{path + ": cannot be read"};
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) return Error{path + ": cannot be read"};
  auto root = parseYaml(text, path);
  if (!root) return Error{root.error()};
  if (!root->isMapping()) {
    return Error{path + ": the top level must be a mapping (" + layout + "), not a list or a value"};
  }
  return read(*root);
}

}  // namespace rgbdslam
