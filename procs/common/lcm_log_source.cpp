#include "common/lcm_log_source.h"

#include "common/lcm_conversions.h"

namespace rgbdslam {
namespace {
constexpr size_t kMaxListedChannels = 16;  // channels named in the "no frames" error at most
}

Expected<std::unique_ptr<LcmLogSource>> LcmLogSource::open(const std::string& path,
                                                           const std::string& channel) {
  auto log = LcmLogReader::open(path);
  if (!log) return Error{log.error()};
  return std::unique_ptr<LcmLogSource>(new LcmLogSource(std::move(*log), channel));
}

Expected<std::unique_ptr<LcmLogSource>> LcmLogSource::fromBytes(const void* bytes, size_t size,
                                                                const std::string& channel) {
  auto log = LcmLogReader::fromBytes(bytes, size, "(log in memory)");
  if (!log) return Error{log.error()};
  return std::unique_ptr<LcmLogSource>(new LcmLogSource(std::move(*log), channel));
}

LcmLogSource::LcmLogSource(LcmLogReader log, std::string channel)
    : log_(std::move(log)), channel_(std::move(channel)) {}

FrameResult LcmLogSource::failed(const std::string& error) const {
  FrameResult result;
  result.status = FrameResult::Status::kFailed;
  result.error = error;
  return result;
}

FrameResult LcmLogSource::next() {
  FrameResult result;
  for (;;) {
    auto event = log_.next();
    if (!event) return failed(event.error());
    if (!*event) break;
    if ((*event)->channel != channel_) {
      if (channels_.size() < kMaxListedChannels) channels_.insert((*event)->channel);
      continue;
    }
    ++channel_events_;
    const std::vector<uint8_t>& data = (*event)->data;
    auto msg = decodeMessage<rgbdslam::rgbd_frame_t>(data.data(), data.size());
    auto frame = msg ? fromLcm(*msg) : Expected<RgbdFrame>(Error{msg.error()});
    if (!frame) {
      result.status = FrameResult::Status::kBadFrame;
      result.error = log_.path() + ": event " + std::to_string((*event)->number) + ": " + frame.error();
      return result;
    }
    result.status = FrameResult::Status::kFrame;
    result.frame = std::move(*frame);
    return result;
  }
  if (channel_events_ == 0) {
    std::string seen;
    for (const auto& name : channels_) seen += (seen.empty() ? "" : ", ") + name;
    return failed(log_.path() + ": no event on channel " + channel_ + " in the whole log (channels: " +
                  (seen.empty() ? "none" : seen) + ")");
  }
  return result;  // kEnd
}

}  // namespace rgbdslam
