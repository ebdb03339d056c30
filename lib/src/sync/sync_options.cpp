#include "rgbdslam/sync/sync_options.h"

namespace rgbdslam {

void SyncOptions::bind(OptionRegistry* r) {
  const std::string s = "sync";
  r->bind(s, "resend_period_s", &outbox.resend_period_s, 1e-3, 3600.0, "s",
          "tracker: first re-send of an unacknowledged keyframe after this; the interval then doubles");
  r->bind(s, "resend_max_period_s", &outbox.resend_max_period_s, 1e-3, 3600.0, "s",
          "tracker: the re-send interval grows to this at most");
  r->bind(s, "resend_max", &outbox.resend_max, 1, 1000, "keyframes",
          "tracker: only the oldest this many unacknowledged keyframes are re-sent (the others as those are acknowledged)");
  r->bind(s, "retained_keyframes", &outbox.retained, 0, 100000, "keyframes",
          "tracker: acknowledged keyframes kept for a mapper whose journal lost them (rgbd-tracker; a keyframe on the link is about 30 kB)");
  r->bind(s, "unacked_in_memory", &outbox.in_memory, 0, 100000, "keyframes",
          "tracker: unacknowledged keyframes kept in memory at most; the newer wait on storage under "
          "tracker.local_map_store_dir (a link outage piles them up; rgbd-tracker; none on storage when that is empty)");
  r->bind(s, "receipt_period_s", &receipt_period_s, 1e-3, 3600.0, "s",
          "tracker: a map receipt (the version it holds) this often");
  r->bind(s, "max_queued_keyframes", &mapper.max_queued_keyframes, 1, 100000, "keyframes",
          "mapper: keyframes held waiting for an earlier one, at most (more are dropped and re-sent)");
  MapPublisherOptions& p = mapper.publisher;
  r->bind(s, "map_period_s", &p.map_period_s, 0.0, 3600.0, "s",
          "mapper: refinement deltas at most this often (a newly integrated keyframe's at once)");
  r->bind(s, "snapshot_period_s", &p.snapshot_period_s, 0.1, 86400.0, "s",
          "mapper: a full map snapshot this often as a fallback, unless the tracker's receipts showed it in step "
          "meanwhile (also one at once when the tracker is stuck behind a lost delta)");
  r->bind(s, "point_move_m", &p.diff.point_move_m, 0.0, 1.0, "m",
          "mapper: a point that moved further than this since last published is sent again");
  r->bind(s, "keyframe_move_m", &p.diff.keyframe_move_m, 0.0, 1.0, "m",
          "mapper: a keyframe whose centre moved further than this since last published is sent again");
  r->bind(s, "keyframe_turn_rad", &p.diff.keyframe_turn_rad, 0.0, 1.0, "rad",
          "mapper: ...or whose orientation turned more than this");
  r->require("sync.resend_max_period_s must not be below sync.resend_period_s", [this] {
    return outbox.resend_max_period_s >= outbox.resend_period_s;
  });
}

}  // namespace rgbdslam
