#pragma once
// The radio link's budget (rgbd-tracker --link-budget-kbps N): a token bucket over everything
// the tracker sends on the link (keyframes, their re-sends, receipts, status) and, with
// counts_received (the default), the map messages it receives: a MAV's radio (a half-duplex
// telemetry link) shares its rate between both directions, and the 1 Mbit/s is for
// keyframes and maps together. The tracker cannot slow the maps, so the keyframes take what
// the maps leave (measured on the full corridor: maps 0.25 Mbit/s of 1.26).
// Why a bucket: a radio link carries a rate on average and absorbs a short burst (its own
// queue); the bucket holds link_burst_s seconds of the budget and refills at the budget's
// rate. Messages that must go although it is empty (below) put it in debt, down to minus its
// capacity at most: the debt is what makes the following keyframes coarser, and the floor
// lets the quality come back within two bursts' time once the load falls.
//
// What the budget does, and does not do:
//   - Quality: each keyframe is encoded once, at a rung of a ladder of encodings chosen by
//     how full the bucket is: the configured encoding while it is at least half full, then
//     coarser depth (every 4th pixel and row), then depth only near the grey image's FAST
//     corners (KeyframeEncoding::depth_near_corners), then JPEG quality in steps of 15 down
//     to keyframe_min_jpeg_quality, then depth at every 8th pixel and row: the last rung,
//     taken as the bucket nears empty (below 1 / (2 (rungs - 1)) of its capacity: 10 % with
//     the default 6 rungs) and when it is empty or in debt. Why depth away from the corners
//     goes before any JPEG quality: the mapper reads no depth there, while its re-finding
//     matches on the JPEG, and a lossier JPEG leaves more keyframes after culling (full
//     corridor through the suite: 1.9-2.0 kept per metre, 1.5 with lossless grey images;
//     docs/open_work.md, session 19). The
//     tracker itself tracks against its own full-quality copy; the mapper's measurements in
//     this keyframe (refinding, epipolar search) use what was sent.
//   - Re-sends, receipts and status are never held back (they count): the mapper takes
//     keyframes strictly in order, so a re-send held while new keyframes keep the bucket
//     empty would stall the map for as long; the outbox's back-off (1, 2, 4 s) bounds them.
//   - New keyframes never wait for the bucket either: one that reaches the mapper seconds
//     late costs more than its bytes save. A waiting line (removed 2026-11-25) ended the full
//     corridor (6.7 keyframes per metre at 1 m/s) at ATE 1.61 m, or lost for good at frame 1516
//     of 3300 with JPEG 75 kept, with a line of 16 (bench-suite). So a new keyframe goes at
//     once, at the last rung if the bucket is empty (counted as over budget).
// So the budget is a target the keyframes' quality follows, not a hard cap: when even the
// last rung is more than the budget at the rate keyframes are made, the rate is exceeded and
// keyframes_over_budget says by how many keyframes.
// Units: rates in kbit/s (1000 bit/s), bytes of LCM payload; time in microseconds from the
// caller's monotonic clock.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/lcm_conversions.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct LinkBudgetOptions {
  double kbps = 1000;           // the link's average rate at most, both ways as counted (0: none) [kbit/s]
  double burst_s = 2.0;         // the bucket holds this many seconds of the budget [s]
  int min_jpeg_quality = 30;    // the ladder's lowest JPEG quality [1, 100]
  bool counts_received = true;  // the maps received count against the budget too
  void bind(OptionRegistry* registry, const std::string& section);
};

class LinkBudget {
 public:
  explicit LinkBudget(const LinkBudgetOptions& options);
  bool limited() const { return options_.kbps > 0; }
  // Adds what the budget allows since the last call (the bucket starts full).
  void refill(int64_t now_us);
  // True when a message may go now: no budget, or the bucket is not empty.
  bool open() const { return !limited() || tokens_ > 0; }
  void spend(size_t bytes);     // sent
  void received(size_t bytes);  // received: counts when counts_received
  // Bucket level / capacity: 1 full, 0 empty, down to -1 in debt (no budget: 1).
  double fill() const;
  int64_t bytesSent() const { return bytes_sent_; }
  int64_t bytesReceived() const { return bytes_received_; }

 private:
  LinkBudgetOptions options_;
  double capacity_bytes_ = 0, tokens_ = 0;
  int64_t last_us_ = -1;
  int64_t bytes_sent_ = 0, bytes_received_ = 0;
  void take(size_t bytes);
};

// best first; every rung is no larger than the one before on any image.
std::vector<KeyframeEncoding> encodingLadder(const KeyframeEncoding& best, int min_jpeg_quality);
// The rung for a bucket at 'fill' (LinkBudget::fill) on a ladder of 'rungs' rungs.
int ladderRung(double fill, int rungs);

}  // namespace rgbdslam
