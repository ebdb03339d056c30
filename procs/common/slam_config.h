#pragma once
// The configuration every algorithm process (rgbd-slam, rgbd-tracker, rgbd-mapper) loads the
// same way: built-in defaults, then --config FILE (config/slam.yaml layout; unknown or
// ill-typed keys are errors), then every --set SECTION.KEY=VALUE,..., then --mode. It holds
// the algorithms' options and the processes' own (channels, periods): one file configures the
// whole suite. The registry describes the effective values.
#include <memory>

#include "common/cli.h"
#include "common/process_options.h"
#include "rgbdslam/system/slam_system.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct SlamConfig {
  // On the heap so that moving SlamConfig keeps the registry's pointers into it valid.
  std::unique_ptr<SlamOptions> slam = std::make_unique<SlamOptions>();
  std::unique_ptr<ProcessOptions> procs = std::make_unique<ProcessOptions>();
  std::unique_ptr<OptionRegistry> registry;  // bound to *slam and *procs
};

// Adds --config, --set (repeatable), --mode and --print-config.
void addSlamConfigOptions(CommandLine& cli);
Expected<SlamConfig> loadSlamConfig(const CommandLine& cli);
// Handles --print-config: prints and returns true when it was given.
bool printConfigIfAsked(const CommandLine& cli, const SlamConfig& config);

}  // namespace rgbdslam
