#include "rgbdslam/sync/map_follower.h"

#include <algorithm>

namespace rgbdslam {

const char* toString(MapVerdict verdict) {
  switch (verdict) {
    case MapVerdict::kApply: return "apply";
    case MapVerdict::kStale: return "stale";
    case MapVerdict::kForeignMap: return "foreign_map";
    case MapVerdict::kMissingDelta: return "missing_delta";
    case MapVerdict::kImplausible: return "implausible";
  }
  return "?";
}

MapVerdict MapFollower::judge(const MapUpdate& update) {
  if (update.map_id != map_id_) return MapVerdict::kForeignMap;
  if (update.version <= version_) return MapVerdict::kStale;
  if (update.version - version_ > max_version_step_) return MapVerdict::kImplausible;
  newest_seen_ = std::max(newest_seen_, update.version);
  if (!update.is_snapshot && update.version != version_ + 1) return MapVerdict::kMissingDelta;
  return MapVerdict::kApply;
}

MapReceipt MapFollower::receipt(int64_t utime, int64_t keyframes_created,
                                int64_t keyframes_unacked) const {
  MapReceipt r;
  r.utime = utime;
  r.map_id = map_id_;
  r.applied_version = version_;
  r.newest_version_seen = newest_seen_;
  r.keyframes_created = keyframes_created;
  r.keyframes_unacked = keyframes_unacked;
  return r;
}

}  // namespace rgbdslam
