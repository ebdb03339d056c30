#include "common/lcm_log_source.h"

#include "common/lcm_conversions.h"

namespace rgbdslam {

Expected<std::unique_ptr<LcmLogSource>> LcmLogSource::open(const std::string& path,
                                                           const std::string& channel) {
  auto log = std::make_unique<lcm::LogFile>(path, "r");
  if (!log->good()) return Error{path + ": cannot open LCM log"};
  return std::unique_ptr<LcmLogSource>(new LcmLogSource(std::move(log), path, channel));
}

LcmLogSource::LcmLogSource(std::unique_ptr<lcm::LogFile> log, std::string path,
                           std::string channel)
    : log_(std::move(log)), path_(std::move(path)), channel_(std::move(channel)) {}

FrameResult LcmLogSource::next() {
  FrameResult result;
  for (const lcm::LogEvent* event = log_->readNextEvent(); event; event = log_->readNextEvent()) {
    if (event->channel != channel_) continue;
    auto msg = decodeMessage<rgbdslam::rgbd_frame_t>(event->data, event->datalen);
    auto frame = msg ? fromLcm(*msg) : Expected<RgbdFrame>(Error{msg.error()});
    if (!frame) {
      result.status = FrameResult::Status::kBadFrame;
      result.error = path_ + ": event " + std::to_string(event->eventnum) + ": " + frame.error();
      return result;
    }
    result.status = FrameResult::Status::kFrame;
    result.frame = std::move(*frame);
    return result;
  }
  return result;  // kEnd
}

}  // namespace rgbdslam
