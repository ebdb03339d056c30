// rgbd-capture: publishes RGB-D frames on RGBD_FRAME from a TUM directory, the synthetic
// renderer, an OpenNI2 device/recording or an LCM log. See --help.
#include <iostream>

#include "common/cli.h"
#include "common/openni2_source.h"
#include "common/process.h"
#include "common/process_options.h"
#include "rgbd-capture/capture.h"

using namespace rgbdslam;

namespace {

CommandLine makeCommandLine() {
  CommandLine cli("rgbd-capture", "Publishes registered colour + depth frames over LCM.");
  cli.option("source", "SRC", "tum:DIR | synth:SCENE[,key=value...] | openni2:URI | lcmlog:FILE[@CHANNEL]");
  cli.option("camera", "FILE", "camera calibration YAML (required for tum:; frames are checked against it)");
  cli.option("rate", "HZ", "publishing rate [frames/s]; 0 = as fast as possible; unset = the recorded timestamps");
  cli.flag("step", "publish one frame per Enter key pressed on standard input");
  cli.option("channel", "NAME", "LCM channel to publish on (the suite's channels.frame)", ChannelOptions{}.frame);
  cli.option("colour", "raw|jpeg", "colour encoding on the wire (raw is lossless)", "raw");
  cli.option("jpeg-quality", "Q", "JPEG quality [1-100] when --colour jpeg", "90");
  cli.option("depth", "raw|zlib", "depth encoding on the wire (both lossless)", "zlib");
  cli.option("max-frames", "N", "stop after N frames; 0 = all", "0");
  cli.option("groundtruth-out", "FILE", "write the source's ground truth (synth:, tum:) to FILE in TUM format");
  cli.option("clock", "recorded|host", "frame utime: as recorded, or shifted so the first frame gets the host clock at publication (live-camera stamps; the ground truth is shifted alike)", "recorded");
  cli.flag("list-devices", "list attached Kinect/PrimeSense USB devices and OpenNI2 devices, then exit");
  addLcmUrlOption(cli);
  return cli;
}

}  // namespace

int main(int argc, char** argv) {
  CommandLine cli = makeCommandLine();
  if (Status parsed = cli.parse(argc, argv); !parsed) return usageError("rgbd-capture", parsed.error());
  if (cli.helpRequested()) {
    std::cout << cli.helpText();
    return 0;
  }
  if (cli.has("list-devices")) {
    std::cout << formatDeviceList();
    return 0;
  }
  auto options = CaptureOptions::fromCommandLine(cli);
  if (!options) return usageError("rgbd-capture", options.error());
  auto capture = Capture::create(*options);
  if (!capture) return usageError("rgbd-capture", capture.error());
  std::cerr << options->describe() << (*capture)->describeSource() << "\n";
  return (*capture)->run(installStopHandlers());
}
