#pragma once
// The tracker's cold keyframes on the flight computer's storage (issue 10, item 3): RTAB-Map's
// split of working memory and long-term memory, for the tracker's local map. A keyframe
// outside the local map (map_replica.h) keeps its pose and small blurry image in memory, for
// relocalisation; its image (the JPEG made when it went cold) and its extras (depth
// surface samples and 3-D features, tracker.cpp) go here, and come back when the camera
// returns. Measured through the suite on the full corridor before this store: the JPEG and
// the extras were about 100 of the 130-150 kB a cold keyframe held, and the tracker grew by
// 15 MB a minute after its first minute (docs/open_work.md).
// Why storage, not the ground station: the link is the scarce resource (1 Mbit/s, issue 10),
// the mapper's copy of a keyframe may be coarser than the tracker's (the link budget sends
// lower resolutions), and returning to a place must not wait for a link that may be down.
// One unnamed file (O_TMPFILE, else mkstemp and unlink at once) under a directory: the
// system removes it when the process ends, however it ends. Bytes are appended; a removed
// entry's bytes are given back to the file system (a punched hole; each entry starts on a
// block of its own so that all its blocks go; the offset only grows, 2^63 bytes). Each entry carries a CRC-32: storage that returns other bytes is an error,
// not a wrong image. The directory must be on storage (flash, disk), not a RAM file system
// (tmpfs), or the bytes are memory again: the default /var/tmp is on storage under the FHS,
// also where /tmp is tmpfs (Debian 13).
// Threads: not thread-safe; the tracker's thread owns it.
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "rgbdslam/map/point_ids.h"
#include "rgbdslam/util/expected.h"

namespace rgbdslam {

class KeyframeStore {
 public:
  // kMessage: an unacknowledged keyframe's message on the link (rgbd-tracker's outbox,
  // procs/common/store_spill.h), in a store of its own. kPoints: the points a cold keyframe
  // describes (map_replica.h).
  enum class Kind : uint8_t { kImage = 0, kExtras = 1, kMessage = 2, kPoints = 3 };

  // An error names the directory and the system's reason (missing, not writable).
  static Expected<std::unique_ptr<KeyframeStore>> open(const std::string& directory);
  ~KeyframeStore();
  KeyframeStore(const KeyframeStore&) = delete;
  KeyframeStore& operator=(const KeyframeStore&) = delete;

  // Replaces any entry of (id, kind) once the new bytes are written (a failed replace leaves
  // the old one; release_later: the old one's bytes are given back by releaseQueued(), as
  // after removeLater). False on a write error (storage full): nothing is stored, the caller
  // keeps the bytes in memory, and later puts fail at once until an entry is removed (no
  // write per frame against a full disk; full()).
  bool put(KeyframeId id, Kind kind, const std::vector<uint8_t>& bytes, bool release_later = false);
  bool full() const { return full_; }
  bool has(KeyframeId id, Kind kind) const { return index_.count(key(id, kind)) > 0; }
  // The bytes as put; an error if there is no entry, the read fails or the bytes changed
  // (then the entry goes: the error is counted once, not on every later try).
  Expected<std::vector<uint8_t>> get(KeyframeId id, Kind kind);
  void remove(KeyframeId id);  // every kind
  void remove(KeyframeId id, Kind kind);
  // As remove(id), but the bytes are given back by releaseQueued(): a punched hole costs 0.2
  // ms (0.6 ms p99 on ext4), and a map version can cull a hundred keyframes at once. The
  // entries are gone at once (has() is false); offsets only grow, so nothing is written
  // where a queued hole will be punched.
  void removeLater(KeyframeId id);
  void removeLater(KeyframeId id, Kind kind);
  // Punches up to 'max' of the queued holes; returns how many are left.
  size_t releaseQueued(size_t max);
  size_t queued() const { return queued_.size(); }
  void clear();

  size_t entries() const { return index_.size(); }
  size_t entries(Kind kind) const { return kind_entries_[static_cast<size_t>(kind)]; }
  int64_t bytes() const { return live_bytes_; }  // of the entries stored now
  int64_t diskBytes() const;                     // the file's blocks on storage now
  int64_t errors() const { return errors_; }     // failed writes and reads so far
  // On tmpfs or ramfs: the stored bytes are memory after all (the processes warn).
  bool inMemory() const { return in_memory_; }
  // The CRC-32 each entry carries: a caller that read an entry can tell whether bytes it
  // would put again are the same, and skip the write.
  static uint32_t checksum(const std::vector<uint8_t>& bytes);

 private:
  struct Entry {
    int64_t offset = 0;
    int64_t size = 0;
    uint32_t crc = 0;
  };
  explicit KeyframeStore(int fd) : fd_(fd) {}
  static constexpr size_t kKinds = 4;
  static uint64_t key(KeyframeId id, Kind kind) {
    return static_cast<uint64_t>(id) * kKinds + static_cast<uint8_t>(kind);  // ids are >= 0
  }
  void release(const Entry& entry);
  std::vector<Entry> queued_;  // removed later (removeLater), not yet given back

  int fd_ = -1;
  int64_t block_ = 4096;  // the file system's block [bytes]; entries start on one
  int64_t end_ = 0;       // the end of the last entry
  int64_t live_bytes_ = 0;
  int64_t errors_ = 0;
  bool full_ = false;
  bool in_memory_ = false;
  std::array<size_t, kKinds> kind_entries_{};
  std::unordered_map<uint64_t, Entry> index_;
};

}  // namespace rgbdslam
