#include "rgbdslam/util/option_registry.h"

#include "rgbdslam/util/yaml_file.h"

#include <algorithm>
#include <cassert>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <sstream>

namespace rgbdslam {
namespace {

constexpr size_t kMaxNameLength = 63;  // LCM's channel name limit [bytes]
constexpr size_t kMaxPathLength = 4095;  // PATH_MAX less its terminating zero [bytes]

std::string formatDouble(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

Expected<double> parseDouble(const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || errno != 0 || !std::isfinite(v)) return Error{"'" + text + "' is not a number"};
  return v;
}

}  // namespace

void OptionRegistry::bind(const std::string& section, const std::string& key, double* field,
                          double min, double max, const std::string& unit, const std::string& help) {
  const std::string name = section + "." + key;
  add({section, key, unit, help, "number", formatDouble(*field),
                      [=](const std::string& text) -> Status {
                        auto v = parseDouble(text);
                        if (!v) return Error{name + ": " + v.error()};
                        if (*v < min || *v > max) return Error{name + ": " + text + " is outside [" + formatDouble(min) + ", " + formatDouble(max) + "]"};
                        *field = *v;
                        return {};
                      },
                      [=] { return formatDouble(*field); }});
}

void OptionRegistry::bind(const std::string& section, const std::string& key, int* field, int min,
                          int max, const std::string& unit, const std::string& help) {
  const std::string name = section + "." + key;
  add({section, key, unit, help, "integer", std::to_string(*field),
                      [=](const std::string& text) -> Status {
                        auto v = parseDouble(text);
                        if (!v || *v != std::floor(*v)) return Error{name + ": '" + text + "' is not a whole number"};
                        if (*v < min || *v > max) return Error{name + ": " + text + " is outside [" + std::to_string(min) + ", " + std::to_string(max) + "]"};
                        *field = static_cast<int>(*v);
                        return {};
                      },
                      [=] { return std::to_string(*field); }});
}

void OptionRegistry::bind(const std::string& section, const std::string& key, bool* field,
                          const std::string& help) {
  const std::string name = section + "." + key;
  add({section, key, "", help, "boolean", *field ? "true" : "false",
                      [=](const std::string& text) -> Status {
                        if (text == "true" || text == "1") *field = true;
                        else if (text == "false" || text == "0") *field = false;
                        else return Error{name + ": '" + text + "' is not true or false"};
                        return {};
                      },
                      [=] { return std::string(*field ? "true" : "false"); }});
}

void OptionRegistry::bindName(const std::string& section, const std::string& key,
                              std::string* field, const std::string& help) {
  const std::string name = section + "." + key;
  add({section, key, "name", help, "name", *field,
       [=](const std::string& text) -> Status {
         const bool plain = std::all_of(text.begin(), text.end(), [](char c) {
           return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '/';
         });
         if (text.empty() || text.size() > kMaxNameLength || !plain) {
           return Error{name + ": '" + text + "' must be 1 to " + std::to_string(kMaxNameLength) +
                        " letters, digits, '_', '-' or '/'"};
         }
         *field = text;
         return {};
       },
       [=] { return *field; }});
}

void OptionRegistry::bindPath(const std::string& section, const std::string& key,
                              std::string* field, const std::string& help) {
  const std::string name = section + "." + key;
  add({section, key, "path", help, "path", *field,
       [=](const std::string& text) -> Status {
         const bool printable = std::all_of(text.begin(), text.end(), [](char c) {
           return static_cast<unsigned char>(c) >= 0x20 && c != 0x7f && c != '"' && c != '\\';
         });
         if (text.size() > kMaxPathLength || !printable) {
           return Error{name + ": '" + text + "' must be at most " + std::to_string(kMaxPathLength) +
                        " printable characters other than '\"' and '\\'"};
         }
         *field = text;
         return {};
       },
       [=] { return *field; }});
}

void OptionRegistry::bind(const std::string& section, const std::string& key, std::string* field,
                          const std::vector<std::string>& choices, const std::string& help) {
  const std::string name = section + "." + key;
  std::string listed;
  for (const auto& c : choices) listed += (listed.empty() ? "" : "|") + c;
  add({section, key, listed, help, "choice", *field,
                      [=](const std::string& text) -> Status {
                        for (const auto& c : choices) {
                          if (c == text) {
                            *field = text;
                            return {};
                          }
                        }
                        return Error{name + ": '" + text + "' is not one of " + listed};
                      },
                      [=] { return *field; }});
}

void OptionRegistry::bindChoice(const std::string& section, const std::string& key,
                                const std::vector<std::string>& names, int current,
                                std::function<void(int)> set_index,
                                std::function<std::string()> show, const std::string& help) {
  assert(current >= 0);  // the field's default is one of the choices
  const std::string name = section + "." + key;
  std::string listed;
  for (const auto& n : names) listed += (listed.empty() ? "" : "|") + n;
  add({section, key, listed, help, "choice", names[static_cast<size_t>(current)],
       [=](const std::string& text) -> Status {
         for (size_t i = 0; i < names.size(); ++i) {
           if (names[i] == text) {
             set_index(static_cast<int>(i));
             return {};
           }
         }
         return Error{name + ": '" + text + "' is not one of " + listed};
       },
       show});
}

void OptionRegistry::add(Entry entry) {
  Entry* existing = find(entry.section, entry.key);
  if (!existing) {
    entries_.push_back(std::move(entry));
    return;
  }
  // A second component's copy of the same option: one value for both.
  assert(existing->kind == entry.kind && existing->default_text == entry.default_text);
  existing->parse = [first = existing->parse, second = entry.parse](const std::string& text) -> Status {
    if (Status s = first(text); !s) return s;
    return second(text);
  };
}

std::vector<std::string> OptionRegistry::sectionsInOrder() const {
  std::vector<std::string> sections;
  for (const auto& e : entries_) {
    if (std::find(sections.begin(), sections.end(), e.section) == sections.end()) {
      sections.push_back(e.section);
    }
  }
  return sections;
}

const OptionRegistry::Entry* OptionRegistry::find(const std::string& section, const std::string& key) const {
  for (const auto& e : entries_) {
    if (e.section == section && e.key == key) return &e;
  }
  return nullptr;
}

OptionRegistry::Entry* OptionRegistry::find(const std::string& section, const std::string& key) {
  return const_cast<Entry*>(static_cast<const OptionRegistry*>(this)->find(section, key));
}

Status OptionRegistry::load(const std::string& path) {
  return readYamlMapping(path, "configuration", "sections such as tracker: ...",
                         [&](const YamlNode& root) { return loadSections(root, path); });
}

Status OptionRegistry::loadSections(const YamlNode& root, const std::string& path) {
  std::set<std::string> sections;
  for (const auto& e : entries_) sections.insert(e.section);
  for (const auto& [section_name, section] : root.entries) {
    const std::string at = path + ":" + std::to_string(section.line) + ": ";
    if (!sections.count(section_name)) return Error{at + "unknown section '" + section_name + "'"};
    if (!section.isMapping()) return Error{at + "section '" + section_name + "' must be a mapping"};
    for (const auto& [key, node] : section.entries) {
      const std::string line = path + ":" + std::to_string(node.line) + ": ";
      Entry* entry = find(section_name, key);
      if (!entry) return Error{line + "unknown key '" + section_name + "." + key + "'"};
      if (!node.isScalar()) return Error{line + section_name + "." + key + " is not a scalar"};
      if (Status s = entry->parse(node.scalar); !s) return Error{line + s.error()};
    }
  }
  return {};
}

void OptionRegistry::require(const std::string& what, std::function<bool()> holds) {
  rules_.push_back({what, std::move(holds)});
}

void OptionRegistry::requireBelow(const std::string& section, const std::string& low,
                                  const std::string& high) {
  const Entry* a = find(section, low);
  const Entry* b = find(section, high);
  assert(a && b && (a->kind == "number" || a->kind == "integer") && (b->kind == "number" || b->kind == "integer"));
  // Entries are found again at check time: entries_ may have grown (and moved) since.
  require(section + "." + low + " must be below " + section + "." + high, [this, section, low, high] {
    return *parseDouble(find(section, low)->show()) < *parseDouble(find(section, high)->show());
  });
  (void)a, (void)b;
}

Status OptionRegistry::validate() const {
  for (const Rule& rule : rules_) {
    if (!rule.holds()) return Error{"contradictory options: " + rule.what + " (" + valuesIn(rule.what) + ")"};
  }
  return {};
}

// "a.b = 1, c.d = 2" for every bound option named in 'text'.
std::string OptionRegistry::valuesIn(const std::string& text) const {
  std::string out;
  for (const auto& e : entries_) {
    const std::string name = e.section + "." + e.key;
    for (size_t at = text.find(name); at != std::string::npos; at = text.find(name, at + 1)) {
      const size_t end = at + name.size();
      if (end < text.size() && (std::isalnum(static_cast<unsigned char>(text[end])) || text[end] == '_')) continue;
      out += (out.empty() ? "" : ", ") + name + " = " + e.show();
      break;
    }
  }
  return out;
}

Status OptionRegistry::set(const std::string& assignment) {
  const size_t dot = assignment.find('.'), eq = assignment.find('=');
  if (dot == std::string::npos || eq == std::string::npos || dot > eq) {
    return Error{"'" + assignment + "' must look like section.key=value"};
  }
  Entry* entry = find(assignment.substr(0, dot), assignment.substr(dot + 1, eq - dot - 1));
  if (!entry) return Error{"unknown option '" + assignment.substr(0, eq) + "'"};
  return entry->parse(assignment.substr(eq + 1));
}

std::string OptionRegistry::describe() const {
  std::ostringstream out;
  for (const std::string& section : sectionsInOrder()) {
    for (const auto& e : entries_) {
      if (e.section != section) continue;
      out << "  " << e.section << "." << e.key << " = " << e.show();
      if (!e.unit.empty()) out << " [" << e.unit << "]";
      out << "\n";
    }
  }
  return out.str();
}

std::string OptionRegistry::markdownTable() const {
  std::ostringstream out;
  out << "| option | unit | default | meaning |\n|---|---|---|---|\n";
  for (const std::string& section : sectionsInOrder()) {
    for (const auto& e : entries_) {
      if (e.section != section) continue;
      out << "| `" << e.section << "." << e.key << "` | " << e.unit << " | " << e.default_text
          << " | " << e.help << " |\n";
    }
  }
  return out.str();
}

std::string OptionRegistry::yamlText() const {
  std::ostringstream out;
  out << "%YAML:1.0\n";
  for (const std::string& section : sectionsInOrder()) {
    out << "\n" << section << ":\n";
    for (const auto& e : entries_) {
      if (e.section != section) continue;
      const bool quoted = e.kind == "choice" || e.kind == "name" || e.kind == "path";
      const std::string value = quoted ? "\"" + e.show() + "\"" : e.show();
      out << "  # " << e.help << (e.unit.empty() ? "" : " [" + e.unit + "]") << "\n";
      out << "  " << e.key << ": " << value << "\n";
    }
  }
  return out.str();
}

}  // namespace rgbdslam
