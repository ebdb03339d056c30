#pragma once
// A small command-line parser shared by every process: "--name value" and "--flag" options,
// positional arguments, and a --help text that lists every option with its unit and default.
// Unknown options and missing values are errors (the process exits with status 2).
#include <map>
#include <string>
#include <vector>

#include "rgbdslam/util/expected.h"

namespace rgbdslam {

class CommandLine {
 public:
  CommandLine(std::string program, std::string summary);
  // An option taking a value; 'help' should say the unit and the default. A repeatable
  // option may be given more than once; get() joins its values with commas.
  void option(const std::string& name, const std::string& value_name, const std::string& help,
              const std::string& default_value = "", bool repeatable = false);
  void flag(const std::string& name, const std::string& help);
  void positional(const std::string& name, const std::string& help);

  // Returns an error for unknown options, missing values or missing positionals.
  // --help is recognised: helpRequested() is then true and nothing else is checked.
  Status parse(int argc, char** argv);
  bool helpRequested() const { return help_requested_; }
  std::string helpText() const;

  bool has(const std::string& name) const;  // given on the command line (or a flag set)
  std::string get(const std::string& name) const;  // the value or its default
  // Numbers: the whole text must parse; NaN, infinities and values beyond long are errors.
  Expected<double> getDouble(const std::string& name) const;
  Expected<long> getInt(const std::string& name) const;
  // The same within [min, max]; the error names the option, the value and the range.
  Expected<double> getDouble(const std::string& name, double min, double max) const;
  Expected<long> getInt(const std::string& name, long min, long max) const;
  const std::string& positionalValue(size_t i) const { return positional_values_.at(i); }

 private:
  struct Spec {
    std::string value_name, help, default_value;
    bool is_flag = false;
    bool repeatable = false;
  };
  std::string program_, summary_;
  std::vector<std::string> order_;
  std::map<std::string, Spec> specs_;
  std::vector<std::pair<std::string, std::string>> positional_specs_;
  std::map<std::string, std::string> values_;
  std::vector<std::string> positional_values_;
  bool help_requested_ = false;
};

// The LCM URL every process accepts. The default stays on this host (ttl=0).
// recv_buf_size: room for a few 640x480 frames (about 1.2 MB each) in the socket buffer; the
// kernel caps it at net.core.rmem_max.
// Periods and durations on the command line are bounded by a day: longer than any run, and
// a period beyond it (or infinite) would silence the messages it paces.
constexpr double kMaxPeriodS = 86400.0;  // [s]

constexpr const char* kDefaultLcmUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
void addLcmUrlOption(CommandLine& cli);

}  // namespace rgbdslam
