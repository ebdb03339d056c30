// rgbd-tracker: the onboard tracker. Tracks every RGBD_FRAME against its replica of the map,
// publishes SLAM_POSE, sends keyframes to the mapper (SLAM_KEYFRAME, re-sent until
// acknowledged) and applies its map versions (SLAM_MAP). See --help.
#include <iostream>
#include <random>

#include "common/cli.h"
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
  cli.option("map-id", "ID", "this session's map id (> 0)", "random");
  cli.option("frame-channel", "NAME", "frames in (local bus)", "RGBD_FRAME");
  cli.option("pose-channel", "NAME", "poses out (local bus)", "SLAM_POSE");
  cli.option("keyframe-channel", "NAME", "keyframes out (link)", "SLAM_KEYFRAME");
  cli.option("map-channel", "NAME", "maps in (link)", "SLAM_MAP");
  cli.option("receipt-channel", "NAME", "map receipts out (link)", "SLAM_MAP_RECEIPT");
  cli.option("status-channel", "NAME", "health reports (link)", "SLAM_STATUS");
  cli.option("status-period", "S", "status reports this often [s]", "1");
  cli.option("max-backlog", "N", "frames waiting to be tracked at most; a newer frame pushes out the oldest [frames]", "2");
  cli.option("keyframe-grey", "jpeg|png", "keyframe image on the link (png is lossless)", "jpeg");
  cli.option("keyframe-jpeg-quality", "Q", "JPEG quality of keyframe images [1-100]", "75");
  cli.option("keyframe-depth", "full|half|quarter", "keyframe depth on the link: every pixel, every 2nd or every 4th pixel and row (the centre of each block)", "quarter");
  cli.option("exit-after-idle", "S", "finish when no frame came for this long; 0 = run until stopped [s]", "0");
  cli.option("ack-wait", "S", "when finishing, wait this long for keyframe acknowledgements [s]", "10");
  addLcmUrlOption(cli);
  return cli;
}

// The map protocol's periods and limits come from the configuration (section "sync").
Expected<TrackerNodeOptions> nodeOptions(const CommandLine& cli, const SyncOptions& sync) {
  TrackerNodeOptions o;
  o.outbox = sync.outbox;
  o.receipt_period_s = sync.receipt_period_s;
  o.frame_channel = cli.get("frame-channel"), o.pose_channel = cli.get("pose-channel");
  o.keyframe_channel = cli.get("keyframe-channel"), o.map_channel = cli.get("map-channel");
  o.status_channel = cli.get("status-channel"), o.receipt_channel = cli.get("receipt-channel");
  for (auto [name, target, min] : {std::tuple{"status-period", &o.status_period_s, 1e-3},
                                   std::tuple{"exit-after-idle", &o.exit_after_idle_s, 0.0},
                                   std::tuple{"ack-wait", &o.ack_wait_s, 0.0}}) {
    auto value = cli.getDouble(name, min, kMaxPeriodS);
    if (!value) return Error{value.error() + " [s]"};
    *target = *value;
  }
  // Frames waiting at most: each is a decoded 640x480 frame (1.5 MB); 1000 is 1.5 GB.
  auto backlog = cli.getInt("max-backlog", 1, 1000);
  if (!backlog) return Error{backlog.error()};
  o.max_backlog_frames = static_cast<int>(*backlog);
  const std::string grey = cli.get("keyframe-grey"), depth = cli.get("keyframe-depth");
  if (grey != "jpeg" && grey != "png") return Error{"--keyframe-grey must be jpeg or png"};
  if (depth != "full" && depth != "half" && depth != "quarter") return Error{"--keyframe-depth must be full, half or quarter"};
  auto quality = cli.getInt("keyframe-jpeg-quality", 1, 100);
  if (!quality) return Error{quality.error()};
  o.encoding = KeyframeEncoding{grey == "jpeg", static_cast<int>(*quality), depth == "full" ? 1 : depth == "half" ? 2 : 4};
  return o;
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
  auto options = nodeOptions(cli, config->slam->sync);
  if (!options) return usageError("rgbd-tracker", options.error());
  auto map_id = mapId(cli);
  if (!map_id) return usageError("rgbd-tracker", map_id.error());
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
                   *map_id, *options);
  const int status = node.run(installStopHandlers());
  node.printSummary();
  return status;
}
