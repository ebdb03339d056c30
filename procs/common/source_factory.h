#pragma once
// Opens a frame source from the command-line form shared by every process:
//   tum:DIR                    a TUM RGB-D directory (needs a camera file for the depth factor)
//   synth:SCENE[,key=value...] the synthetic renderer (see parseSyntheticSpec)
//   openni2:URI                Dummy, a .oni file, a device URI, or "any"
//   lcmlog:FILE[@CHANNEL]      rgbd_frame_t messages from an LCM log (default RGBD_FRAME)
#include <memory>
#include <optional>
#include <string>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/io/frame_source.h"
#include "rgbdslam/io/trajectory_io.h"
#include "rgbdslam/util/expected.h"

namespace rgbdslam {

struct SourceSpec {
  std::string kind;  // "tum", "synth", "openni2", "lcmlog"
  std::string argument;
};
Expected<SourceSpec> parseSourceSpec(const std::string& text);

// 'camera' is required for tum:, optional elsewhere (frames are then checked against it).
Expected<std::unique_ptr<FrameSource>> openSource(const std::string& text,
                                                  const std::optional<PinholeCamera>& camera);

// The camera a synthetic source renders with (for processes that need one without a file).
Expected<PinholeCamera> syntheticCamera(const std::string& text);

// Ground truth that comes with a source: DIR/groundtruth.txt for tum:, the rendered
// trajectory for synth:; nullopt when there is none (openni2:, lcmlog:).
std::optional<Trajectory> groundTruthFor(const std::string& text);

}  // namespace rgbdslam
