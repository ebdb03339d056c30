// rgbd-mapper: the ground station's mapper. Integrates the tracker's keyframes (SLAM_KEYFRAME)
// in order, runs bundle adjustment, publishes the map (SLAM_MAP) and its health
// (MAPPER_STATUS), and journals its keyframes so a restart loses nothing. See --help.
#include <filesystem>
#include <iostream>

#include "common/cli.h"
#include "common/process.h"
#include "common/slam_config.h"
#include "rgbd-mapper/mapper_node.h"
#include "rgbdslam/camera/calibration_io.h"

using namespace rgbdslam;

namespace {

CommandLine makeCommandLine() {
  CommandLine cli("rgbd-mapper", "Builds the map from the tracker's keyframes and publishes it.");
  cli.option("camera", "FILE", "camera calibration YAML (the tracker's camera)");
  addSlamConfigOptions(cli);
  cli.option("state-dir", "DIR", "folder of the persisted map (journal); 'none' persists nothing", "mapper-state");
  cli.flag("fresh", "start a new map: move an existing journal aside (map.journal.old) first");
  cli.option("keyframe-channel", "NAME", "keyframes from the tracker", "SLAM_KEYFRAME");
  cli.option("map-channel", "NAME", "map versions to the tracker", "SLAM_MAP");
  cli.option("status-channel", "NAME", "health reports", "MAPPER_STATUS");
  cli.option("receipt-channel", "NAME", "the tracker's map receipts (the version it holds)", "SLAM_MAP_RECEIPT");
  cli.option("status-period", "S", "status reports this often [s]", "1");
  addLcmUrlOption(cli);
  return cli;
}

// The map protocol's periods and limits come from the configuration (section "sync").
Expected<MapperNodeOptions> nodeOptions(const CommandLine& cli, const SyncOptions& sync) {
  MapperNodeOptions o;
  o.sync = sync.mapper;
  o.keyframe_channel = cli.get("keyframe-channel");
  o.map_channel = cli.get("map-channel");
  o.status_channel = cli.get("status-channel");
  o.receipt_channel = cli.get("receipt-channel");
  o.state_dir = cli.get("state-dir") == "none" ? "" : cli.get("state-dir");
  auto period = cli.getDouble("status-period", 1e-3, kMaxPeriodS);
  if (!period) return Error{period.error() + " [s]"};
  o.status_period_s = *period;
  return o;
}

// --fresh: keeps the previous journal as map.journal.old rather than deleting it.
Status moveJournalAside(const std::string& dir) {
  std::error_code error;
  const std::filesystem::path journal = std::filesystem::path(dir) / "map.journal";
  if (!std::filesystem::exists(journal)) return Status{};
  std::filesystem::rename(journal, journal.string() + ".old", error);
  if (error) return Error{"cannot move " + journal.string() + " aside: " + error.message()};
  return Status{};
}

}  // namespace

int main(int argc, char** argv) {
  CommandLine cli = makeCommandLine();
  if (Status parsed = cli.parse(argc, argv); !parsed) return usageError("rgbd-mapper", parsed.error());
  if (cli.helpRequested()) {
    std::cout << cli.helpText();
    return 0;
  }
  auto config = loadSlamConfig(cli);
  if (!config) return usageError("rgbd-mapper", config.error());
  if (printConfigIfAsked(cli, *config)) return 0;
  if (!cli.has("camera")) return usageError("rgbd-mapper", "--camera is required (see --help)");
  auto camera = loadCamera(cli.get("camera"));
  if (!camera) return usageError("rgbd-mapper", camera.error());
  auto options = nodeOptions(cli, config->slam->sync);
  if (!options) return usageError("rgbd-mapper", options.error());
  if (cli.has("fresh") && !options->state_dir.empty()) {
    if (Status moved = moveJournalAside(options->state_dir); !moved) return usageError("rgbd-mapper", moved.error());
  }
  auto lcm = openLcm(cli.get("lcm-url"));
  if (!lcm) return usageError("rgbd-mapper", lcm.error());
  std::cerr << "rgbd-mapper: camera " << camera->name << ", state "
            << (options->state_dir.empty() ? "not persisted" : options->state_dir) << ", lcm-url "
            << cli.get("lcm-url") << "\nconfiguration:\n" << config->registry->describe();

  MapperNode node(lcm->get(), *camera, config->slam->mapper, *parseSlamMode(config->slam->mode), *options);
  if (Status restored = node.restore(); !restored) return usageError("rgbd-mapper", restored.error());
  node.run(installStopHandlers());
  node.printSummary();
  return 0;
}
