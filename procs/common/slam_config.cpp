#include "common/slam_config.h"

#include <iostream>
#include <sstream>

namespace rgbdslam {
namespace {

// Splits "a=1,b=2" into assignments; commas inside values are not supported.
std::vector<std::string> splitAssignments(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

}  // namespace

void addSlamConfigOptions(CommandLine& cli) {
  cli.option("mode", "M", "mono | depth-init | depth-ba (overrides slam.mode)", "depth-ba");
  cli.option("config", "FILE", "SLAM configuration (see config/slam.yaml)", "built-in defaults");
  cli.option("set", "SECTION.KEY=VALUE", "override configuration options: SECTION.KEY=VALUE[,...]; may be given more than once", "", /*repeatable=*/true);
  cli.option("print-config", "yaml|markdown", "print the effective configuration (loadable YAML, or a table) and exit");
}

Expected<SlamConfig> loadSlamConfig(const CommandLine& cli) {
  SlamConfig config;
  config.registry = std::make_unique<OptionRegistry>();
  config.slam->bind(config.registry.get());
  config.procs->bind(config.registry.get());
  if (cli.has("config")) {
    if (Status s = config.registry->load(cli.get("config")); !s) return Error{s.error()};
  }
  for (const std::string& assignment : splitAssignments(cli.get("set"))) {
    if (Status s = config.registry->set(assignment); !s) return Error{"--set: " + s.error()};
  }
  if (cli.has("mode")) {
    if (Status s = config.registry->set("slam.mode=" + cli.get("mode")); !s) return Error{"--mode: " + s.error()};
  }
  // rgbd-tracker's --link-budget-kbps N, the and the README's name for the key.
  if (cli.has("link-budget-kbps")) {
    if (Status s = config.registry->set("tracker_node.link_budget_kbps=" + cli.get("link-budget-kbps")); !s) {
      return Error{"--link-budget-kbps: " + s.error()};
    }
  }
  if (Status s = config.registry->validate(); !s) {
    return Error{(cli.has("config") ? cli.get("config") + " with --set/--mode: " : "") + s.error()};
  }
  return config;
}

bool printConfigIfAsked(const CommandLine& cli, const SlamConfig& config) {
  if (!cli.has("print-config")) return false;
  const bool markdown = cli.get("print-config") == "markdown";
  std::cout << (markdown ? config.registry->markdownTable() : config.registry->yamlText());
  return true;
}

}  // namespace rgbdslam
