#pragma once
// Frames from an LCM log file (as written by lcm-logger): the rgbd_frame_t messages on one
// channel, in log order. Messages that do not decode are reported as kBadFrame and skipped.
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>

#include "rgbdslam/io/frame_source.h"
#include "rgbdslam/util/expected.h"

namespace rgbdslam {

class LcmLogSource : public FrameSource {
 public:
  static Expected<std::unique_ptr<LcmLogSource>> open(const std::string& path,
                                                      const std::string& channel);
  FrameResult next() override;
  double nominalRateHz() const override { return 0.0; }
  std::optional<size_t> size() const override { return std::nullopt; }
  std::string describe() const override { return "lcmlog:" + path_ + "@" + channel_; }

 private:
  LcmLogSource(std::unique_ptr<lcm::LogFile> log, std::string path, std::string channel);
  std::unique_ptr<lcm::LogFile> log_;
  std::string path_, channel_;
};

}  // namespace rgbdslam
