// rgbd-tracker: the onboard tracker. Tracks every RGBD_FRAME against its replica of the map,
// publishes SLAM_POSE, sends keyframes to the mapper (SLAM_KEYFRAME, re-sent until
// acknowledged) and applies its map versions (SLAM_MAP). See --help.
#include <iostream>
#include <optional>
#include <random>

#include "common/cli.h"
#include "common/frame_log.h"
#include "common/map_start.h"
#include "common/process.h"
#include "common/slam_config.h"
#include "rgbd-tracker/tracker_node.h"
#include "rgbdslam/camera/calibration_io.h"

using namespace rgbdslam;

namespace {

CommandLine makeCommandLine() {
  CommandLine cli("rgbd-tracker", "Tracks the camera against the mapper's map, at camera rate.");
  cli.option("camera", "FILE", "camera calibration YAML");
  addSlamConfigOptions(cli);
  cli.option("link-url", "URL", "LCM URL of the link to the mapper (keyframes, maps, status)", "the --lcm-url");
  // Channels, periods and the keyframe encoding are configuration (sections channels,
  // tracker_node, sync): --config FILE or --set, e.g. --set tracker_node.exit_after_idle_s=2.
  cli.option("map-id", "ID", "this session's map id (> 0); with --load-map the id the mapper serves the file as", "random");
  cli.option("load-map", "FILE", "start from the map in FILE (made with this camera and mode; rgbd-mapper --load-map the same file); "
             "the first frames relocalise in it");
  cli.option("link-budget-kbps", "N", "the link's average rate at most, what the tracker sends and the maps it receives [kbit/s] (0: none); "
             "overrides tracker_node.link_budget_kbps", "the configuration's");
  cli.option("frame-log", "FILE.csv", "one line per frame tracked: state, points, pose sigma, track_ms, latency_ms, ... "
             "(the columns: common/frame_log.h)");
  cli.flag("localise-only", "with --load-map: track in the loaded map, add no keyframes");
  addLcmUrlOption(cli);
  return cli;
}

Expected<int64_t> mapId(const CommandLine& cli) {
  if (!cli.has("map-id")) {
    std::random_device random;
    std::uniform_int_distribution<int64_t> id(1, (int64_t{1} << 62));
    return id(random);
  }
  auto id = cli.getInt("map-id", 1, int64_t{1} << 62);
  if (!id) return Error{id.error()};
  return static_cast<int64_t>(*id);
}

// --load-map FILE (with --map-id, so that tracker and mapper name the loaded map alike) and
// --localise-only (only with --load-map).
Status startMapIfAsked(const CommandLine& cli, const PinholeCamera& camera, SlamMode mode,
                       std::optional<LoadedMap>* start_map) {
  if (!cli.has("load-map")) {
    if (cli.has("localise-only")) return Error{"--localise-only needs --load-map FILE (the map to localise in)"};
    return Status{};
  }
  if (!cli.has("map-id")) return Error{"--load-map needs --map-id ID, the id rgbd-mapper --load-map serves the map as"};
  auto loaded = loadStartMap(cli.get("load-map"), camera, mode);
  if (!loaded) return Error{loaded.error()};
  std::cerr << "rgbd-tracker: starting from " << cli.get("load-map") << " (" << loaded->keyframes.size() << " keyframes, "
            << loaded->points.size() << " points)" << (cli.has("localise-only") ? ", localising only" : "") << "\n";
  start_map->emplace(std::move(*loaded));
  return Status{};
}

}  // namespace

int main(int argc, char** argv) {
  CommandLine cli = makeCommandLine();
  if (Status parsed = cli.parse(argc, argv); !parsed) return usageError("rgbd-tracker", parsed.error());
  if (cli.helpRequested()) {
    std::cout << cli.helpText();
    return 0;
  }
  auto config = loadSlamConfig(cli);
  if (!config) return usageError("rgbd-tracker", config.error());
  if (printConfigIfAsked(cli, *config)) return 0;
  if (!cli.has("camera")) return usageError("rgbd-tracker", "--camera is required (see --help)");
  auto camera = loadCamera(cli.get("camera"));
  if (!camera) return usageError("rgbd-tracker", camera.error());
  auto map_id = mapId(cli);
  if (!map_id) return usageError("rgbd-tracker", map_id.error());
  std::optional<LoadedMap> start_map;
  if (Status s = startMapIfAsked(cli, *camera, *parseSlamMode(config->slam->mode), &start_map); !s) {
    return usageError("rgbd-tracker", s.error());
  }
  FrameLog frame_log;
  if (cli.has("frame-log")) {
    auto opened = FrameLog::open(cli.get("frame-log"));
    if (!opened) return usageError("rgbd-tracker", opened.error());
    frame_log = std::move(*opened);
  }
  auto local = openLcm(cli.get("lcm-url"));
  if (!local) return usageError("rgbd-tracker", local.error());
  std::unique_ptr<lcm::LCM> own_link;
  if (cli.has("link-url") && cli.get("link-url") != cli.get("lcm-url")) {
    auto link = openLcm(cli.get("link-url"));
    if (!link) return usageError("rgbd-tracker", link.error());
    own_link = std::move(*link);
  }
  lcm::LCM* link = own_link ? own_link.get() : local->get();
  std::cerr << "rgbd-tracker: camera " << camera->name << ", map " << *map_id << ", lcm-url "
            << cli.get("lcm-url") << ", link-url " << (own_link ? cli.get("link-url") : "(the same)")
            << "\nconfiguration:\n" << config->registry->describe();

  TrackerNode node(local->get(), link, *camera, config->slam->tracker, *parseSlamMode(config->slam->mode),
                   *map_id,
                   TrackerNodeOptions{config->procs->channels, config->procs->tracker_node, config->slam->sync});
  if (!node.keyframeStoreStatus()) return usageError("rgbd-tracker", node.keyframeStoreStatus().error());
  warnIfStoreInMemory("rgbd-tracker", node.keyframeStore());
  if (start_map) node.startFrom(*start_map, cli.has("localise-only"));
  node.logFramesTo(std::move(frame_log));
  const int status = node.run(installStopHandlers());
  node.printSummary();
  return status;
}
