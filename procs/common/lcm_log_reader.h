#pragma once
// Reads an LCM event log (as lcm-logger writes it) and checks every length itself: liblcm
// 1.3.1's reader trusts an event's data length (0x7fffffff: a failed malloc, then a write
// through NULL). Format, per event, big-endian: sync word 0xEDA1DA01, int64 event number,
// int64 timestamp [us], int32 channel length, int32 data length, the channel, the data.
// A channel must be 1..kMaxChannelBytes long (LCM's own limit is 63); the data must fit in
// what is left of the file and in kMaxEventBytes. A file that is empty or does not start
// with the sync word is refused at open(); a bad sync word, an impossible length or a torn
// event later is an error naming the event and its offset. Memory: one event at a time.
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rgbdslam/util/expected.h"

namespace rgbdslam {

struct LcmLogEvent {
  int64_t number = 0;    // event number as written by the logger
  int64_t utime = 0;     // receive time [us]
  std::string channel;
  std::vector<uint8_t> data;
};

class LcmLogReader {
 public:
  static constexpr uint32_t kSyncWord = 0xEDA1DA01;
  static constexpr int32_t kMaxChannelBytes = 255;      // LCM allows 63; room for other tools
  static constexpr int64_t kMaxEventBytes = 1 << 28;    // [bytes] 256 MB: ~200 raw 640x480 frames

  static Expected<LcmLogReader> open(const std::string& path);
  // Reads from a copy of 'bytes' (tests and fuzzing); 'name' stands for the path in errors.
  static Expected<LcmLogReader> fromBytes(const void* bytes, size_t size, const std::string& name);

  // The next event; nullopt at the end of the file; an error when the file is malformed (the
  // reader then stays at the error).
  Expected<std::optional<LcmLogEvent>> next();
  const std::string& path() const { return path_; }

 private:
  struct Closer {
    void operator()(FILE* file) const { std::fclose(file); }
  };
  LcmLogReader(FILE* file, std::string path, int64_t size, std::shared_ptr<std::vector<uint8_t>> memory);
  static Expected<LcmLogReader> start(LcmLogReader reader);
  Status read(void* out, size_t bytes, int64_t event_offset, const char* what);
  Error fail(const std::string& what);

  std::unique_ptr<FILE, Closer> file_;
  std::string path_;
  int64_t size_ = 0;      // [bytes] of the whole file
  int64_t offset_ = 0;    // [bytes] read so far
  std::string error_;     // set once the file proved malformed
  std::shared_ptr<std::vector<uint8_t>> memory_;  // backing store of fromBytes()
};

}  // namespace rgbdslam
