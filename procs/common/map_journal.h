#pragma once
// The mapper's persistent state: an append-only journal of the keyframes it integrated (the
// keyframe_t messages as received, in id order) and of the map versions it published. A
// restarted mapper re-integrates the keyframes (the mapper is deterministic, so it rebuilds
// an equivalent map) and continues the version numbers after the last one published, so a
// tracker never sees a version go backwards.
// Record layout: magic "MJ1" + type byte, payload length (u32), CRC-32 of the payload (u32),
// payload; little-endian. Types: 1 a keyframe (its keyframe_t message), 2 a version (i64),
// 3 keyframes culled (i64 ids; written before the publication that names them). Each record is written with one write(2) and flushed with
// fdatasync before the mapper acts on it (before a keyframe is acknowledged, before a version
// is published). A torn record at the end (the process killed mid-write) fails its length or
// CRC check: load() drops it and truncates the file there, and says so.
#include <cstdint>
#include <string>
#include <vector>

#include "rgbdslam/sync/mapper_sync.h"
#include "rgbdslam/util/expected.h"

namespace rgbdslam {

class MapJournal : public KeyframeJournal {
 public:
  struct Contents {
    std::vector<std::vector<uint8_t>> keyframes;  // encoded keyframe_t, in journal order
    int64_t last_version = 0;                     // last published map version (0: none)
    std::vector<KeyframeId> culled;               // keyframes the mapper culled, in order
    std::string warning;                          // e.g. a torn record that was dropped
  };
  // Opens (creating if needed) DIR/map.journal and reads what it holds.
  static Expected<MapJournal> open(const std::string& dir, Contents* contents);
  MapJournal(MapJournal&& other) noexcept;
  MapJournal& operator=(MapJournal&& other) noexcept;
  MapJournal(const MapJournal&) = delete;
  MapJournal& operator=(const MapJournal&) = delete;
  ~MapJournal() override;

  // The keyframe's message as received (IncomingKeyframe::encoded).
  Status appendKeyframe(const IncomingKeyframe& keyframe) override;
  Status appendKeyframe(const void* data, size_t size);
  Status appendVersion(int64_t version) override;
  Status appendCulled(const std::vector<KeyframeId>& ids) override;
  const std::string& path() const { return path_; }

 private:
  MapJournal(int fd, std::string path) : fd_(fd), path_(std::move(path)) {}
  Status append(uint8_t type, const void* data, size_t size);
  int fd_ = -1;
  std::string path_;
};

}  // namespace rgbdslam
