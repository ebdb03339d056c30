#include "common/source_factory.h"

#include "common/lcm_log_source.h"
#include "common/openni2_source.h"
#include "common/process_options.h"
#include "rgbdslam/synth/scene.h"
#include "rgbdslam/io/tum_dataset.h"

namespace rgbdslam {
Expected<SourceSpec> parseSourceSpec(const std::string& text) {
  const size_t colon = text.find(':');
  if (colon == std::string::npos || colon == 0) {
    return Error{"source '" + text + "' must look like tum:DIR, synth:SCENE, openni2:URI or lcmlog:FILE"};
  }
  SourceSpec spec{text.substr(0, colon), text.substr(colon + 1)};
  if (spec.kind != "tum" && spec.kind != "synth" && spec.kind != "openni2" && spec.kind != "lcmlog") {
    return Error{"unknown source kind '" + spec.kind + "' (tum, synth, openni2, lcmlog)"};
  }
  if (spec.argument.empty() && spec.kind != "openni2") return Error{"source '" + text + "' names nothing after the colon"};
  return spec;
}

Expected<std::unique_ptr<FrameSource>> openSource(const std::string& text,
                                                  const std::optional<PinholeCamera>& camera) {
  auto spec = parseSourceSpec(text);
  if (!spec) return Error{spec.error()};
  if (spec->kind == "tum") {
    if (!camera) return Error{"tum: sources need a camera file (--camera) for the depth factor"};
    auto source = openTumDataset(spec->argument, *camera);
    if (!source) return Error{source.error()};
    return std::unique_ptr<FrameSource>(std::move(*source));
  }
  if (spec->kind == "synth") {
    auto options = parseSyntheticSpec(spec->argument);
    if (!options) return Error{options.error()};
    return makeSyntheticSource(*options);
  }
  if (spec->kind == "openni2") return openOpenNI2Source(spec->argument, OpenNI2Options{});
  std::string path = spec->argument, channel = ChannelOptions{}.frame;
  const size_t at = path.rfind('@');
  if (at != std::string::npos) {
    channel = path.substr(at + 1);
    path = path.substr(0, at);
  }
  auto log = LcmLogSource::open(path, channel);
  if (!log) return Error{log.error()};
  return std::unique_ptr<FrameSource>(std::move(*log));
}

Expected<PinholeCamera> syntheticCamera(const std::string& text) {
  auto spec = parseSourceSpec(text);
  if (!spec) return Error{spec.error()};
  if (spec->kind != "synth") return Error{"not a synthetic source: " + text};
  auto options = parseSyntheticSpec(spec->argument);
  if (!options) return Error{options.error()};
  return SyntheticScene(*options).camera();
}

std::optional<Trajectory> groundTruthFor(const std::string& text) {
  auto spec = parseSourceSpec(text);
  if (!spec) return std::nullopt;
  if (spec->kind == "synth") {
    auto options = parseSyntheticSpec(spec->argument);
    if (!options) return std::nullopt;
    return SyntheticScene(*options).groundTruth();
  }
  if (spec->kind == "tum") {
    auto trajectory = readTumTrajectory(spec->argument + "/groundtruth.txt");
    if (trajectory) return *trajectory;
  }
  return std::nullopt;
}

}  // namespace rgbdslam
