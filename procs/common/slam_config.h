#pragma once
// The SLAM configuration every algorithm process loads the same way: built-in defaults,
// then --config FILE (config/slam.yaml layout; unknown or ill-typed keys are errors), then
// --set SECTION.KEY=VALUE,..., then --mode. The registry describes the effective values.
#include <memory>

#include "common/cli.h"
#include "rgbdslam/system/slam_system.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct SlamConfig {
  // On the heap so that moving SlamConfig keeps the registry's pointers into it valid.
  std::unique_ptr<SlamOptions> slam = std::make_unique<SlamOptions>();
  std::unique_ptr<OptionRegistry> registry;  // bound to *slam
};

// Adds --config, --set, --mode and --print-config.
void addSlamConfigOptions(CommandLine& cli);
Expected<SlamConfig> loadSlamConfig(const CommandLine& cli);
// Handles --print-config: prints and returns true when it was given.
bool printConfigIfAsked(const CommandLine& cli, const SlamConfig& config);

}  // namespace rgbdslam
