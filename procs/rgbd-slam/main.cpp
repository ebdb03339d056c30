// rgbd-slam: tracker and mapper in one process over any source; writes the trajectory and
// prints ATE when ground truth is at hand. See --help.
#include <iostream>

#include "common/cli.h"
#include "common/process.h"
#include "rgbd-slam/batch_runner.h"

using namespace rgbdslam;

namespace {

CommandLine makeCommandLine() {
  CommandLine cli("rgbd-slam", "Runs tracking and mapping over a whole sequence.");
  cli.option("source", "SRC", "tum:DIR | synth:SCENE[,key=value...] | openni2:URI | lcmlog:FILE[@CHANNEL]");
  cli.option("camera", "FILE", "camera calibration YAML (required except for synth:)");
  cli.option("output", "TRAJ.txt", "trajectory in TUM format (every frame that got a pose, as published: map corrections taken in at tracker.correction_rate_*)");
  cli.option("frame-log", "FILE.csv", "one line per frame read: status, tracking state, points found, quality, pose sigma, map correction, made a keyframe, track_ms, loss reason, ... (the columns: common/frame_log.h)");
  cli.flag("deterministic", "process every frame; the mapper finishes each keyframe before the next frame");
  cli.option("link-loss", "P", "deterministic: tracker and mapper talk over a simulated link losing this fraction of messages each way [0-1]", "0");
  cli.option("link-delay-ms", "MS", "deterministic: ...delaying every message this long, in the frames' time [ms]", "0");
  cli.option("link-seed", "N", "deterministic: seed of the simulated link's losses", "1");
  cli.option("keyframe-rung", "N", "keyframes reach the mapper encoded and decoded as rgbd-tracker sends them, at this rung of its encoding ladder (0: tracker_node.keyframe_*; each higher rung coarser, as the link budget chooses: procs/common/link_budget.h; encoded in the frame loop after the pose, outside track_ms); -1: as the tracker made them", "-1");
  addSlamConfigOptions(cli);
  cli.option("groundtruth", "FILE", "ground truth in TUM format", "the source's own, if any");
  cli.option("max-frames", "N", "stop after N frames; 0 = all", "0");
  cli.option("save-map", "FILE", "at the end, save the mapper's map to FILE (docs/design.md, \"Map files\"; written whole or not at all)");
  cli.option("load-map", "FILE", "start from the map in FILE (made with this camera and mode) and extend it; the first frames relocalise in it");
  cli.flag("localise-only", "with --load-map: track in the loaded map only; no keyframes are added and the map is not changed");
  cli.flag("quiet", "no progress line");
  addLcmUrlOption(cli);  // accepted like every process; lcmlog: sources are read from the file
  return cli;
}

}  // namespace

int main(int argc, char** argv) {
  CommandLine cli = makeCommandLine();
  if (Status parsed = cli.parse(argc, argv); !parsed) return usageError("rgbd-slam", parsed.error());
  if (cli.helpRequested()) {
    std::cout << cli.helpText();
    return 0;
  }
  auto options = BatchOptions::fromCommandLine(cli);
  if (!options) return usageError("rgbd-slam", options.error());
  if (printConfigIfAsked(cli, options->config)) return 0;
  auto runner = BatchRunner::create(std::move(*options));
  if (!runner) return usageError("rgbd-slam", runner.error());
  return (*runner)->run(installStopHandlers());
}
