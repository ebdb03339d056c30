#pragma once
// The tracker's side of map versions (docs/design.md, "Map protocol"): which map messages
// its replica may apply. A message of another map is foreign; a version at or below the one
// applied is stale (a repeat, or from before a restart); a delta applies only directly after
// its predecessor (a delta after a lost one would leave the replica a mix of versions: the
// follower waits for a snapshot, which the mapper sends when the receipts show the gap); a
// snapshot applies whenever it is newer. A version further ahead than max_version_step is
// implausible (the mapper counts one per publication) and refused, so one forged message
// cannot freeze the tracker's version.
// Acknowledgements of keyframes are taken from every message of this map, applied or not:
// see TrackerSync.
// Threads: not thread-safe.
#include <cstdint>

#include "rgbdslam/map/map_types.h"

namespace rgbdslam {

enum class MapVerdict {
  kApply,         // in order: apply it
  kStale,         // version <= the applied one
  kForeignMap,    // another map id
  kMissingDelta,  // a delta whose predecessor was not applied
  kImplausible,   // a version further ahead than max_version_step
};
const char* toString(MapVerdict verdict);

class MapFollower {
 public:
  static constexpr int64_t kDefaultMaxVersionStep = int64_t{1} << 32;
  explicit MapFollower(int64_t map_id, int64_t max_version_step = kDefaultMaxVersionStep)
      : map_id_(map_id), max_version_step_(max_version_step) {}
  // Judges a received update (and notes its version as seen when it is of this map).
  MapVerdict judge(const MapUpdate& update);
  // The caller applied 'update' (after kApply).
  void applied(const MapUpdate& update) { version_ = update.version; }
  MapReceipt receipt(int64_t utime, int64_t keyframes_created, int64_t keyframes_unacked) const;

  int64_t mapId() const { return map_id_; }
  int64_t version() const { return version_; }
  int64_t newestSeen() const { return newest_seen_; }

 private:
  int64_t map_id_;
  int64_t max_version_step_;
  int64_t version_ = 0;      // applied
  int64_t newest_seen_ = 0;  // of this map, plausible, applied or not
};

}  // namespace rgbdslam
