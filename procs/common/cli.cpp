#include "common/cli.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace rgbdslam {

CommandLine::CommandLine(std::string program, std::string summary)
    : program_(std::move(program)), summary_(std::move(summary)) {}

void CommandLine::option(const std::string& name, const std::string& value_name,
                         const std::string& help, const std::string& default_value,
                         bool repeatable) {
  order_.push_back(name);
  specs_[name] = Spec{value_name, help, default_value, false, repeatable};
}

void CommandLine::flag(const std::string& name, const std::string& help) {
  order_.push_back(name);
  specs_[name] = Spec{"", help, "", true};
}

void CommandLine::positional(const std::string& name, const std::string& help) {
  positional_specs_.emplace_back(name, help);
}

Status CommandLine::parse(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      help_requested_ = true;
      return {};
    }
    if (arg.rfind("--", 0) != 0) {
      positional_values_.push_back(arg);
      continue;
    }
    std::string name = arg.substr(2), value;
    const size_t eq = name.find('=');
    const bool inline_value = eq != std::string::npos;
    if (inline_value) {
      value = name.substr(eq + 1);
      name = name.substr(0, eq);
    }
    const auto spec = specs_.find(name);
    if (spec == specs_.end()) return Error{"unknown option --" + name + " (see --help)"};
    if (spec->second.is_flag) {
      if (inline_value) return Error{"option --" + name + " takes no value"};
      values_[name] = "1";
      continue;
    }
    if (!inline_value) {
      if (i + 1 >= argc) return Error{"option --" + name + " needs a value (" + spec->second.value_name + ")"};
      value = argv[++i];
    }
    const auto given = values_.find(name);
    if (given != values_.end() && spec->second.repeatable) {
      given->second += "," + value;
    } else {
      values_[name] = value;
    }
  }
  if (positional_values_.size() < positional_specs_.size()) {
    return Error{"missing argument " + positional_specs_[positional_values_.size()].first + " (see --help)"};
  }
  if (positional_values_.size() > positional_specs_.size()) {
    return Error{"unexpected argument '" + positional_values_[positional_specs_.size()] + "' (see --help)"};
  }
  return {};
}

std::string CommandLine::helpText() const {
  std::ostringstream out;
  out << "usage: " << program_;
  for (const auto& [name, help] : positional_specs_) out << " " << name;
  out << " [options]\n" << summary_ << "\n";
  if (!positional_specs_.empty()) out << "\narguments:\n";
  for (const auto& [name, help] : positional_specs_) out << "  " << name << "\n      " << help << "\n";
  out << "\noptions:\n";
  for (const auto& name : order_) {
    const Spec& spec = specs_.at(name);
    out << "  --" << name << (spec.is_flag ? "" : " " + spec.value_name) << "\n      " << spec.help;
    if (!spec.default_value.empty()) out << " (default: " << spec.default_value << ")";
    out << "\n";
  }
  out << "  --help\n      print this text and exit\n";
  return out.str();
}

bool CommandLine::has(const std::string& name) const { return values_.count(name) > 0; }

std::string CommandLine::get(const std::string& name) const {
  const auto it = values_.find(name);
  if (it != values_.end()) return it->second;
  return specs_.at(name).default_value;
}

namespace {

std::string numberText(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

}  // namespace

Expected<double> CommandLine::getDouble(const std::string& name) const {
  const std::string text = get(name);
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || errno != 0) return Error{"--" + name + ": '" + text + "' is not a number"};
  if (!std::isfinite(value)) return Error{"--" + name + ": '" + text + "' is not a finite number"};
  return value;
}

Expected<double> CommandLine::getDouble(const std::string& name, double min, double max) const {
  auto value = getDouble(name);
  if (!value) return value;
  if (*value < min || *value > max) {
    return Error{"--" + name + ": " + get(name) + " is outside [" + numberText(min) + ", " + numberText(max) + "]"};
  }
  return value;
}

Expected<long> CommandLine::getInt(const std::string& name) const {
  const std::string text = get(name);
  char* end = nullptr;
  errno = 0;
  const long value = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0') return Error{"--" + name + ": '" + text + "' is not a whole number"};
  if (errno == ERANGE) return Error{"--" + name + ": " + text + " is too large"};
  if (errno != 0) return Error{"--" + name + ": '" + text + "' is not a whole number"};
  return value;
}

Expected<long> CommandLine::getInt(const std::string& name, long min, long max) const {
  auto value = getInt(name);
  if (!value) return value;
  if (*value < min || *value > max) {
    return Error{"--" + name + ": " + get(name) + " is outside [" + std::to_string(min) + ", " + std::to_string(max) + "]"};
  }
  return value;
}

void addLcmUrlOption(CommandLine& cli) {
  cli.option("lcm-url", "URL",
             "LCM provider URL; ttl=0 keeps traffic on this host, ttl=1 crosses one link",
             kDefaultLcmUrl);
}

}  // namespace rgbdslam
