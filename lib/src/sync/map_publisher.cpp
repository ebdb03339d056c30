#include "rgbdslam/sync/map_publisher.h"

#include <algorithm>

namespace rgbdslam {

const char* toString(ReceiptVerdict verdict) {
  switch (verdict) {
    case ReceiptVerdict::kNoted: return "noted";
    case ReceiptVerdict::kSnapshotAsked: return "snapshot_asked";
    case ReceiptVerdict::kForeignMap: return "foreign_map";
    case ReceiptVerdict::kCaughtUp: return "caught_up";
    case ReceiptVerdict::kImplausible: return "implausible";
  }
  return "?";
}

MapPublisher::MapPublisher(const MapPublisherOptions& options)
    : options_(options), differ_(options.diff) {}

void MapPublisher::start(int64_t map_id, int64_t last_version) {
  map_id_ = map_id;
  version_ = last_version;
  last_snapshot_version_ = last_version;
  snapshot_due_ = true;
  pending_ = MapChanges{};
  last_receipt_version_ = -1;
  same_receipts_ = behind_receipts_ = 0;
}

void MapPublisher::startAfterLoss(int64_t map_id, int64_t tracker_version) {
  start(map_id, tracker_version);
  snapshot_due_ = false;
  ack_due_ = true;
}

void MapPublisher::note(const MapChanges& changes, bool integrated) {
  pending_.merge(changes);
  integrated_unpublished_ = integrated_unpublished_ || integrated;
}

ReceiptVerdict MapPublisher::onReceipt(const MapReceipt& receipt) {
  if (!started() || receipt.map_id != map_id_) return ReceiptVerdict::kForeignMap;
  const int64_t claimed = std::max(receipt.applied_version, receipt.newest_version_seen);
  if (receipt.applied_version < 0 || receipt.newest_version_seen < 0 ||
      claimed - version_ > MapFollower::kDefaultMaxVersionStep) {
    return ReceiptVerdict::kImplausible;
  }
  if (claimed > version_) {
    version_ = claimed;  // the next version is newer than anything the tracker holds
    snapshot_due_ = true;
    ++versions_caught_up_;
    return ReceiptVerdict::kCaughtUp;
  }
  const bool holds_unapplied = receipt.newest_version_seen > receipt.applied_version &&
                               receipt.newest_version_seen > last_snapshot_version_;
  const bool same = receipt.applied_version == last_receipt_version_;
  same_receipts_ = same ? same_receipts_ + 1 : 1;
  behind_receipts_ = same && receipt.applied_version < version_at_last_receipt_ ? behind_receipts_ + 1 : 0;
  last_receipt_version_ = receipt.applied_version;
  version_at_last_receipt_ = version_;
  in_step_ = in_step_ || (receipt.applied_version > 0 && receipt.applied_version == receipt.newest_version_seen &&
                          (receipt.applied_version == version_ || same_receipts_ == 1));
  // Below the last snapshot, the snapshot may still be on its way (a large one over a slow
  // link): give it two more receipt periods before asking again.
  const int needed = receipt.applied_version >= last_snapshot_version_ ? 2 : 4;
  const bool stuck = behind_receipts_ >= needed - 1;
  if (snapshot_due_ || !(holds_unapplied || stuck)) return ReceiptVerdict::kNoted;
  snapshot_due_ = true;
  ++snapshots_asked_;
  return ReceiptVerdict::kSnapshotAsked;
}

std::optional<MapUpdate> MapPublisher::publishDue(const Map& map, KeyframeId acked_below,
                                                  int64_t now_us) {
  if (!started()) return std::nullopt;
  bool fallback = elapsed(fallback_from_us_, now_us, options_.snapshot_period_s);
  if (fallback && in_step_ && !snapshot_due_) {  // the receipts showed the tracker in step
    fallback = in_step_ = false;
    fallback_from_us_ = now_us;
    ++snapshots_skipped_;
  }
  const bool snapshot = snapshot_due_ || fallback;
  const bool refinement_time = elapsed(last_refinement_us_, now_us, options_.map_period_s);
  const bool refinement_due = (!pending_.empty() || ack_due_) && refinement_time;
  if (!snapshot && !integrated_unpublished_ && !refinement_due) return std::nullopt;
  MapChanges held_back;  // moves that wait for the next refinement
  MapUpdate update = snapshot ? differ_.snapshot(map)
                              : differ_.delta(map, pending_, refinement_time ? nullptr : &held_back);
  update.utime = now_us;
  update.map_id = map_id_;
  update.version = ++version_;
  update.is_snapshot = snapshot;
  update.acked_below = std::max<KeyframeId>(acked_below, 0);
  pending_ = std::move(held_back);
  if (snapshot || refinement_time) last_refinement_us_ = now_us;
  integrated_unpublished_ = ack_due_ = false;
  if (snapshot) {
    ++snapshots_published_;
    fallback_from_us_ = now_us;
    in_step_ = false;
    last_snapshot_version_ = version_;
    snapshot_due_ = false;
    last_receipt_version_ = -1;  // judge the tracker again from its next receipts
    same_receipts_ = behind_receipts_ = 0;
  }
  return update;
}

}  // namespace rgbdslam
