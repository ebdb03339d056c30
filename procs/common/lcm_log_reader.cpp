#include "common/lcm_log_reader.h"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace rgbdslam {
namespace {

constexpr int64_t kHeaderBytes = 4 + 8 + 8 + 4 + 4;  // sync, number, utime, channel and data lengths

uint64_t bigEndian(const uint8_t* in, size_t bytes) {
  uint64_t value = 0;
  for (size_t i = 0; i < bytes; ++i) value = (value << 8) | in[i];
  return value;
}

}  // namespace

LcmLogReader::LcmLogReader(FILE* file, std::string path, int64_t size,
                           std::shared_ptr<std::vector<uint8_t>> memory)
    : file_(file), path_(std::move(path)), size_(size), memory_(std::move(memory)) {}

Expected<LcmLogReader> LcmLogReader::open(const std::string& path) {
  FILE* file = std::fopen(path.c_str(), "rb");
  if (!file) return Error{path + ": cannot open LCM log: " + std::strerror(errno)};
  struct stat info {};
  if (::fstat(fileno(file), &info) != 0 || !S_ISREG(info.st_mode)) {
    std::fclose(file);
    return Error{path + ": not a regular file, cannot be an LCM log"};
  }
  return start(LcmLogReader(file, path, static_cast<int64_t>(info.st_size), nullptr));
}

Expected<LcmLogReader> LcmLogReader::fromBytes(const void* bytes, size_t size, const std::string& name) {
  if (size == 0) return Error{name + ": is empty, not an LCM log"};
  auto memory = std::make_shared<std::vector<uint8_t>>(static_cast<const uint8_t*>(bytes),
                                                       static_cast<const uint8_t*>(bytes) + size);
  FILE* file = fmemopen(memory->data(), memory->size(), "rb");
  if (!file) return Error{name + ": cannot read from memory: " + std::strerror(errno)};
  return start(LcmLogReader(file, name, static_cast<int64_t>(size), std::move(memory)));
}

// A log must start with an event: empty files and other files are refused at once.
Expected<LcmLogReader> LcmLogReader::start(LcmLogReader reader) {
  if (reader.size_ == 0) return Error{reader.path_ + ": is empty, not an LCM log"};
  uint8_t sync[4];
  if (reader.size_ < 4 || std::fread(sync, 1, 4, reader.file_.get()) != 4 || bigEndian(sync, 4) != kSyncWord) {
    return Error{reader.path_ + ": not an LCM log (it does not start with the event sync word 0xEDA1DA01)"};
  }
  if (std::fseek(reader.file_.get(), 0, SEEK_SET) != 0) return Error{reader.path_ + ": cannot rewind"};
  return Expected<LcmLogReader>(std::move(reader));
}

Error LcmLogReader::fail(const std::string& what) {
  error_ = path_ + ": " + what;
  return Error{error_};
}

Status LcmLogReader::read(void* out, size_t bytes, int64_t event_offset, const char* what) {
  if (bytes == 0) return Status{};
  if (std::fread(out, 1, bytes, file_.get()) != bytes) {
    return fail("the event at offset " + std::to_string(event_offset) + " is truncated (its " + what +
                " is cut off at the end of the file)");
  }
  offset_ += static_cast<int64_t>(bytes);
  return Status{};
}

Expected<std::optional<LcmLogEvent>> LcmLogReader::next() {
  if (!error_.empty()) return Error{error_};
  if (offset_ == size_) return std::optional<LcmLogEvent>();
  const int64_t at = offset_;
  uint8_t header[kHeaderBytes];
  if (Status s = read(header, sizeof header, at, "header"); !s) return Error{s.error()};
  if (bigEndian(header, 4) != kSyncWord) {
    return fail("bad sync word at offset " + std::to_string(at) + " (a corrupt or torn log)");
  }
  LcmLogEvent event;
  event.number = static_cast<int64_t>(bigEndian(header + 4, 8));
  event.utime = static_cast<int64_t>(bigEndian(header + 12, 8));
  const auto channel_length = static_cast<int32_t>(static_cast<uint32_t>(bigEndian(header + 20, 4)));
  const auto data_length = static_cast<int32_t>(static_cast<uint32_t>(bigEndian(header + 24, 4)));
  const std::string where = "event " + std::to_string(event.number) + " at offset " + std::to_string(at);
  if (channel_length < 1 || channel_length > kMaxChannelBytes) {
    return fail(where + " has a channel length of " + std::to_string(channel_length) + ", outside [1, " +
                std::to_string(kMaxChannelBytes) + "]");
  }
  const int64_t left = size_ - offset_ - channel_length;
  if (data_length < 0 || data_length > kMaxEventBytes || data_length > left) {
    return fail(where + " claims " + std::to_string(data_length) + " data bytes; " +
                std::to_string(std::max<int64_t>(left, 0)) + " are left in the file (limit " +
                std::to_string(kMaxEventBytes) + ")");
  }
  event.channel.resize(static_cast<size_t>(channel_length));
  if (Status s = read(event.channel.data(), event.channel.size(), at, "channel"); !s) return Error{s.error()};
  event.data.resize(static_cast<size_t>(data_length));
  if (Status s = read(event.data.data(), event.data.size(), at, "data"); !s) return Error{s.error()};
  return std::optional<LcmLogEvent>(std::move(event));
}

}  // namespace rgbdslam
