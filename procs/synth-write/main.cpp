// synth-write: renders a synthetic scene and writes it as a TUM RGB-D directory (rgb/,
// depth/, rgb.txt, depth.txt, groundtruth.txt), for tools that read the benchmark's layout.
#include <iostream>

#include "common/cli.h"
#include "common/process.h"
#include "rgbdslam/synth/scene.h"

using namespace rgbdslam;

int main(int argc, char** argv) {
  CommandLine cli("synth-write", "Writes a synthetic sequence as a TUM RGB-D directory.");
  cli.positional("SCENE", "room, corridor, flight, office or twins, with ,key=value options as in "
                          "synth:SCENE (seed, frames, rate, depth_fraction, depth, effects, ...)");
  cli.positional("DIR", "output directory (created; existing files are overwritten)");
  addLcmUrlOption(cli);  // accepted like every process; nothing is sent
  if (Status s = cli.parse(argc, argv); !s) return usageError("synth-write", s.error());
  if (cli.helpRequested()) return std::cout << cli.helpText(), 0;
  auto options = parseSyntheticSpec(cli.positionalValue(0));
  if (!options) return usageError("synth-write", options.error());
  const SyntheticScene scene(*options);
  std::cerr << "synth-write: " << scene.numFrames() << " frames of " << cli.positionalValue(0)
            << " to " << cli.positionalValue(1) << "\n";
  const Status written = scene.writeTumDirectory(cli.positionalValue(1));
  if (!written) {
    std::cerr << "synth-write: error: " << written.error() << "\n";
    return 1;
  }
  return 0;
}
