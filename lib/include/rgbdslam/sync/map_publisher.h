#pragma once
// The one map publisher (docs/design.md, "Map protocol"): decides when the mapper's map goes
// out, numbers the versions and builds each message.
//   - A newly integrated keyframe is published at once (its acknowledgement stops the
//     tracker's re-sends); refinement results (points and keyframes that moved) at most
//     every map_period_s: a keyframe's publication in between carries what is new and what
//     was removed, and the moves wait. Why: keyframes come several times a second in a
//     corridor, and each bundle adjustment moves the window's points again; sent with every
//     keyframe, moves were 78 % of the map bytes over the full corridor (4.9 of 6.3 MB of
//     deltas), most of them the same points again a few hundred ms later.
//   - Deltas carry what changed since the last publication, above the thresholds
//     (map/map_diff.h); every message acknowledges the integrated keyframes (acked_below).
//   - Snapshots (the whole map): the first publication after start() (a start or a restart
//     from the journal), every snapshot_period_s as a fallback unless a receipt in that
//     period showed the tracker in step (it held every version it had seen, and either the
//     newest published or a newer one than at its previous receipt: a snapshot would repeat
//     what it holds, and it grows with the map: 449 kB after the flight's 2 minutes, 29 % of
//     its map bytes), and when the tracker's
//     receipts show it stuck behind a lost delta: at once when a receipt shows a version
//     seen but not applied (newer than the last snapshot), and when receipts in a row show
//     the same applied version below the published one (the lost delta was the last): two
//     receipts, or four while that version is below the last snapshot's (which may still be
//     on its way). Below what was published when the previous receipt came, not merely now:
//     a version published just before a receipt may still be on its way or waiting behind a
//     frame, and a tracker in step was asked a snapshot that way 8 times over the 10-minute
//     flight through the suite (no delta lost; each snapshot 7.5-45.5 ms of the tracking
//     thread's time at 15 000-47 000 points).
//   - A receipt that claims a version this publisher never published comes from a tracker
//     that holds versions of a mapper run whose journal was cut short (a corrupt record):
//     the versions go on after the tracker's, with a snapshot, so that the tracker takes them
//     (it never goes backwards). A claim further ahead than the tracker itself would accept
//     (MapFollower's step) is implausible: counted and ignored.
// Time: 'now_us' from the caller's monotonic clock [us]. Threads: not thread-safe (the
// caller, MapperSync, serialises).
#include <optional>

#include "rgbdslam/map/map_diff.h"
#include "rgbdslam/sync/map_follower.h"

namespace rgbdslam {

struct MapPublisherOptions {
  double map_period_s = 1.0;        // refinement deltas at most this often [s]
  double snapshot_period_s = 30.0;  // full snapshots at least this often [s]
  MapDiffOptions diff;  // bound in section "sync" (sync_options.h)
};

enum class ReceiptVerdict {
  kNoted,             // nothing to do
  kSnapshotAsked,     // the next publication is a snapshot
  kForeignMap,        // a receipt for another map
  kCaughtUp,          // claims a version never published: versions go on after it
  kImplausible,       // claims a version too far ahead to be true
};
const char* toString(ReceiptVerdict verdict);

class MapPublisher {
 public:
  explicit MapPublisher(const MapPublisherOptions& options = {});
  // Publishes map 'map_id' from version last_version + 1 on; the first is a snapshot.
  void start(int64_t map_id, int64_t last_version);
  // A mapper that lost its whole journal and holds nothing yet takes over the tracker's map
  // at the tracker's version: its first publication is an empty delta (no snapshot that
  // would empty the tracker's replica), which acknowledges no keyframe, so the tracker sends
  // again the acknowledged keyframes it retains (TrackerSync).
  void startAfterLoss(int64_t map_id, int64_t tracker_version);
  // The mapper's changes since the last call; 'integrated': they include a new keyframe.
  void note(const MapChanges& changes, bool integrated);
  // A duplicate keyframe arrived (its acknowledgement was probably lost): acknowledge again
  // with the next refinement publication.
  void acknowledgementDue() { ack_due_ = true; }
  ReceiptVerdict onReceipt(const MapReceipt& receipt);
  // The next version when one is due at now_us (the baseline and the version advance);
  // 'acked_below': keyframes with smaller ids are integrated.
  std::optional<MapUpdate> publishDue(const Map& map, KeyframeId acked_below, int64_t now_us);

  bool started() const { return map_id_ != 0; }
  int64_t mapId() const { return map_id_; }
  int64_t version() const { return version_; }
  long snapshotsPublished() const { return snapshots_published_; }
  long snapshotsAsked() const { return snapshots_asked_; }
  long versionsCaughtUp() const { return versions_caught_up_; }
  long snapshotsSkipped() const { return snapshots_skipped_; }

 private:
  bool elapsed(int64_t since_us, int64_t now_us, double period_s) const {
    return since_us < 0 || now_us - since_us >= static_cast<int64_t>(period_s * 1e6);
  }
  MapPublisherOptions options_;
  MapDiffer differ_;
  MapChanges pending_;                 // noted, not yet published
  int64_t map_id_ = 0;                 // 0: not started
  int64_t version_ = 0;                // last published
  int64_t last_snapshot_version_ = 0;
  int64_t fallback_from_us_ = -1;  // the fallback period runs from here (a snapshot, or a skip)
  bool in_step_ = false;           // a receipt in this period showed the tracker in step
  int64_t last_refinement_us_ = -1;   // last publication that carried the moves (or a snapshot)
  bool snapshot_due_ = true, integrated_unpublished_ = false, ack_due_ = false;
  int64_t last_receipt_version_ = -1;  // applied version in the previous receipt
  int same_receipts_ = 0;              // receipts in a row with that version
  int64_t version_at_last_receipt_ = 0;  // version_ when the previous receipt came
  // Receipts in a row with the same applied version, below what had been published when the
  // one before came: the tracker had a whole receipt period to take a newer version.
  int behind_receipts_ = 0;
  long snapshots_published_ = 0, snapshots_asked_ = 0, versions_caught_up_ = 0;
  long snapshots_skipped_ = 0;  // fallback snapshots not sent: the tracker was in step
};

}  // namespace rgbdslam
