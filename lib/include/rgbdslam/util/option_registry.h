#pragma once
// One loader for every component's options. Each options struct (defaults in-class) binds
// its fields here with a unit and a meaning; load() reads a YAML file (util/yaml_file.h)
// with one mapping per section and rejects unknown sections, unknown keys and ill-typed or
// out-of-range values, naming the key and the file (also a file whose top level is not a
// mapping); describe() prints the effective configuration. Options that depend on each other
// (a minimum and its maximum) are checked together by validate(), once every value is set.
// Call order: bind all fields and rules, load() (optional), set() (optional), validate(),
// describe().
// One option may feed several components: binding a section.key that is already bound (same
// kind, same default) adds the field as another target, so that e.g. noise.sigma_2d_k sets
// the tracker's and the bundle adjuster's copy of the noise model alike. Output lists each
// option once, sections in the order they were first bound.
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "rgbdslam/util/expected.h"
#include "rgbdslam/util/yaml_file.h"

namespace rgbdslam {

class OptionRegistry {
 public:
  void bind(const std::string& section, const std::string& key, double* field, double min,
            double max, const std::string& unit, const std::string& help);
  void bind(const std::string& section, const std::string& key, int* field, int min, int max,
            const std::string& unit, const std::string& help);
  void bind(const std::string& section, const std::string& key, bool* field,
            const std::string& help);
  // A name chosen freely (an LCM channel, for one): 1 to 63 letters, digits, '_', '-' or
  // '/' (LCM's limit on a channel name is 63 bytes; LCM subscribes by regular expression, so
  // a name keeps clear of the characters that would make it match other channels).
  void bindName(const std::string& section, const std::string& key, std::string* field,
                const std::string& help);
  // A file or directory path: empty (the option's help says what that means) or up to
  // 4095 printable characters other than '"' and '\' (so that the YAML the registry writes
  // reads back); whether it exists is for its user to check.
  void bindPath(const std::string& section, const std::string& key, std::string* field,
                const std::string& help);
  // A string restricted to 'choices'.
  void bind(const std::string& section, const std::string& key, std::string* field,
            const std::vector<std::string>& choices, const std::string& help);
  // An enumeration written as one of the names in 'choices'.
  template <typename Enum>
  void bind(const std::string& section, const std::string& key, Enum* field,
            const std::vector<std::pair<std::string, Enum>>& choices, const std::string& help) {
    std::vector<std::string> names;
    int current = -1;
    for (size_t i = 0; i < choices.size(); ++i) {
      names.push_back(choices[i].first);
      if (choices[i].second == *field) current = static_cast<int>(i);
    }
    bindChoice(section, key, names, current,
               [field, choices](int i) { *field = choices[static_cast<size_t>(i)].second; },
               [field, choices] {
                 for (const auto& [name, value] : choices) {
                   if (value == *field) return name;
                 }
                 return std::string("?");
               },
               help);
  }

  // A rule between options, checked by validate(): 'holds' is true when the values agree;
  // 'what' states the rule in words, naming the keys ("tracker.a must be below tracker.b").
  void require(const std::string& what, std::function<bool()> holds);
  // The rule "section.low < section.high" for two numeric options bound before.
  void requireBelow(const std::string& section, const std::string& low, const std::string& high);
  // Every rule; the first broken one is an error that shows the values involved.
  Status validate() const;

  Status load(const std::string& path);
  // Sets one option from "section.key=value" (command-line overrides).
  Status set(const std::string& assignment);
  std::string describe() const;  // "section.key = value  [unit] help" per line
  // Markdown table of every option with unit, default and meaning (for docs).
  std::string markdownTable() const;
  // A loadable YAML file of every option at its current value, commented with unit and
  // meaning (config/slam.yaml is this output for the defaults).
  std::string yamlText() const;

 private:
  struct Entry {
    std::string section, key, unit, help, kind, default_text;
    std::function<Status(const std::string&)> parse;  // from text
    std::function<std::string()> show;
  };
  struct Rule {
    std::string what;
    std::function<bool()> holds;
  };
  Entry* find(const std::string& section, const std::string& key);
  // Adds the entry, or chains its parse onto an existing one of the same name (see above).
  void add(Entry entry);
  void bindChoice(const std::string& section, const std::string& key,
                  const std::vector<std::string>& names, int current,
                  std::function<void(int)> set_index, std::function<std::string()> show,
                  const std::string& help);
  std::vector<std::string> sectionsInOrder() const;
  const Entry* find(const std::string& section, const std::string& key) const;
  Status loadSections(const YamlNode& root, const std::string& path);
  std::string valuesIn(const std::string& text) const;
  std::vector<Entry> entries_;
  std::vector<Rule> rules_;
};

}  // namespace rgbdslam
