// rgbd-mapper: the ground station's mapper. Integrates the tracker's keyframes (SLAM_KEYFRAME)
// in order, runs bundle adjustment, publishes the map (SLAM_MAP) and its health
// (MAPPER_STATUS), and journals its keyframes so a restart loses nothing. See --help.
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>

#include "common/cli.h"
#include "common/map_start.h"
#include "common/process.h"
#include "common/slam_config.h"
#include "rgbd-mapper/mapper_node.h"
#include "rgbdslam/camera/calibration_io.h"
#include "rgbdslam/io/trajectory_io.h"

using namespace rgbdslam;

namespace {

CommandLine makeCommandLine() {
  CommandLine cli("rgbd-mapper", "Builds the map from the tracker's keyframes and publishes it.");
  cli.option("camera", "FILE", "camera calibration YAML (the tracker's camera)");
  addSlamConfigOptions(cli);
  cli.option("state-dir", "DIR", "folder of the persisted map (journal); 'none' persists nothing", "mapper-state");
  cli.option("load-map", "FILE", "start from the map in FILE (made with this camera and mode) and serve it as map --map-id "
             "to a tracker started with the same file and id; a restart repeats both (its journal then holds what was added)");
  cli.option("map-id", "ID", "with --load-map: the id the map is served as (> 0; the tracker's --map-id)");
  cli.flag("fresh", "start a new map: move an existing journal aside (map.journal.old) first");
  cli.option("keyframes-out", "FILE", "at exit, write the map's keyframes at their final poses (loops closed, parts "
             "joined; a part never joined stays in its own frame) as a TUM trajectory, as ORB-SLAM2's "
             "KeyFrameTrajectory.txt (default: none)");
  // Channels and periods are configuration (sections channels, mapper_node, sync).
  addLcmUrlOption(cli);
  return cli;
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

// --load-map FILE with --map-id ID (neither without the other).
Status startMapIfAsked(const CommandLine& cli, const PinholeCamera& camera, SlamMode mode,
                       std::optional<LoadedMap>* start_map, int64_t* map_id) {
  if (cli.has("load-map") != cli.has("map-id")) {
    return Error{"--load-map FILE and --map-id ID go together: the map in FILE is served as map ID"};
  }
  if (!cli.has("load-map")) return Status{};
  auto id = cli.getInt("map-id", 1, int64_t{1} << 62);
  if (!id) return Error{id.error()};
  auto loaded = loadStartMap(cli.get("load-map"), camera, mode);
  if (!loaded) return Error{loaded.error()};
  std::cerr << "rgbd-mapper: starting from " << cli.get("load-map") << " (" << loaded->keyframes.size()
            << " keyframes, " << loaded->points.size() << " points) as map " << *id << "\n";
  *map_id = static_cast<int64_t>(*id);
  start_map->emplace(std::move(*loaded));
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
  std::optional<LoadedMap> start_map;
  int64_t map_id = 0;
  if (Status s = startMapIfAsked(cli, *camera, *parseSlamMode(config->slam->mode), &start_map, &map_id); !s) {
    return usageError("rgbd-mapper", s.error());
  }
  const MapperNodeOptions options{config->procs->channels, config->procs->mapper_node, config->slam->sync.mapper,
                                  cli.get("state-dir") == "none" ? "" : cli.get("state-dir")};
  if (cli.has("fresh") && !options.state_dir.empty()) {
    if (Status moved = moveJournalAside(options.state_dir); !moved) return usageError("rgbd-mapper", moved.error());
  }
  // --keyframes-out is written at exit: a path that cannot be written is refused now, not after
  // the flight (opened to append: an earlier run's file stays until the exit's write replaces it).
  if (cli.has("keyframes-out") && !std::ofstream(cli.get("keyframes-out"), std::ios::app)) {
    return usageError("rgbd-mapper", "--keyframes-out: cannot write " + cli.get("keyframes-out"));
  }
  auto lcm = openLcm(cli.get("lcm-url"));
  if (!lcm) return usageError("rgbd-mapper", lcm.error());
  std::cerr << "rgbd-mapper: camera " << camera->name << ", state "
            << (options.state_dir.empty() ? "not persisted" : options.state_dir) << ", lcm-url "
            << cli.get("lcm-url") << "\nconfiguration:\n" << config->registry->describe();

  MapperNode node(lcm->get(), *camera, config->slam->mapper, *parseSlamMode(config->slam->mode), options);
  if (Status restored = node.restore(start_map ? &*start_map : nullptr, map_id); !restored) return usageError("rgbd-mapper", restored.error());
  node.run(installStopHandlers());
  node.printSummary();
  if (cli.has("keyframes-out")) {
    if (Status written = writeTumTrajectory(cli.get("keyframes-out"), keyframeTrajectory(node.map())); !written) {
      std::cerr << "rgbd-mapper: error: " << written.error() << "\n";
      return 1;
    }
  }
  return 0;
}
