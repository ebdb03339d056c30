#pragma once
// Frames from an LCM log file (as written by lcm-logger): the rgbd_frame_t messages on one
// channel, in log order, read by LcmLogReader (which checks every length itself).
// A message that does not decode is reported as kBadFrame and skipped. A file that is not an
// LCM log fails at open(); a malformed or torn event later, or a log that ends without a
// single event on the channel, is kFailed (the processes then exit non-zero).
#include <memory>
#include <set>
#include <string>

#include "common/lcm_log_reader.h"
#include "rgbdslam/io/frame_source.h"
#include "rgbdslam/util/expected.h"

namespace rgbdslam {

class LcmLogSource : public FrameSource {
 public:
  static Expected<std::unique_ptr<LcmLogSource>> open(const std::string& path,
                                                      const std::string& channel);
  // The same over a log held in memory (tests and fuzzing).
  static Expected<std::unique_ptr<LcmLogSource>> fromBytes(const void* bytes, size_t size,
                                                           const std::string& channel);
  FrameResult next() override;
  double nominalRateHz() const override { return 0.0; }
  std::optional<size_t> size() const override { return std::nullopt; }
  std::string describe() const override { return "lcmlog:" + log_.path() + "@" + channel_; }

 private:
  LcmLogSource(LcmLogReader log, std::string channel);
  FrameResult failed(const std::string& error) const;
  LcmLogReader log_;
  std::string channel_;
  long channel_events_ = 0;          // events seen on channel_, good or bad
  std::set<std::string> channels_;   // every channel seen (the first few), for the error
};

}  // namespace rgbdslam
