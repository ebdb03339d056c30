#include "common/link_budget.h"

#include <algorithm>
#include <cmath>

namespace rgbdslam {

void LinkBudgetOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "link_budget_kbps", &kbps, 0.0, 1e6, "kbit/s",
          "the link's average rate at most: what the tracker sends (keyframes, re-sends, receipts, status) and, "
          "with link_budget_counts_maps, the maps it receives; keyframes get coarser (JPEG quality, "
          "depth resolution) as it is spent, nothing is dropped or delayed (0: no budget; also --link-budget-kbps)");
  r->bind(s, "link_budget_counts_maps", &counts_received,
          "the maps the tracker receives count against the budget too (a half-duplex radio shares its rate between both directions)");
  r->bind(s, "link_burst_s", &burst_s, 0.1, 60.0, "s", "the link absorbs a burst of this many seconds of the budget");
  r->bind(s, "keyframe_min_jpeg_quality", &min_jpeg_quality, 1, 100, "",
          "the lowest JPEG quality the budget may choose for a keyframe");
}

LinkBudget::LinkBudget(const LinkBudgetOptions& options)
    : options_(options), capacity_bytes_(options.kbps * 1000.0 / 8.0 * options.burst_s),
      tokens_(capacity_bytes_) {}

void LinkBudget::refill(int64_t now_us) {
  if (last_us_ >= 0 && now_us > last_us_) {
    tokens_ = std::min(capacity_bytes_, tokens_ + options_.kbps * 1000.0 / 8.0 * (now_us - last_us_) * 1e-6);
  }
  last_us_ = std::max(last_us_, now_us);
}

void LinkBudget::spend(size_t bytes) {
  bytes_sent_ += static_cast<int64_t>(bytes);
  take(bytes);
}

void LinkBudget::received(size_t bytes) {
  bytes_received_ += static_cast<int64_t>(bytes);
  if (options_.counts_received) take(bytes);
}

void LinkBudget::take(size_t bytes) {
  if (limited()) tokens_ = std::max(-capacity_bytes_, tokens_ - static_cast<double>(bytes));
}

double LinkBudget::fill() const { return limited() ? tokens_ / capacity_bytes_ : 1.0; }

std::vector<KeyframeEncoding> encodingLadder(const KeyframeEncoding& best, int min_jpeg_quality) {
  std::vector<KeyframeEncoding> ladder{best};
  KeyframeEncoding rung = best;
  if (rung.depth_step < 4) {
    rung.depth_step = 4;
    ladder.push_back(rung);
  }
  if (!rung.depth_near_corners) {
    rung.depth_near_corners = true;
    ladder.push_back(rung);
  }
  if (!rung.jpeg_grey) {  // lossless PNG: JPEG at 90 (or the floor, if higher) is the first lossy rung
    rung.jpeg_grey = true;
    rung.jpeg_quality = std::max(90, min_jpeg_quality);
    ladder.push_back(rung);
  }
  while (rung.jpeg_quality > min_jpeg_quality) {
    rung.jpeg_quality = std::max(min_jpeg_quality, rung.jpeg_quality - 15);
    ladder.push_back(rung);
  }
  if (rung.depth_step < 8) {
    rung.depth_step = 8;
    ladder.push_back(rung);
  }
  return ladder;
}

int ladderRung(double fill, int rungs) {
  if (rungs <= 1 || fill >= 0.5) return 0;
  const double below = (0.5 - std::max(fill, 0.0)) / 0.5;  // (0, 1]
  return std::clamp(static_cast<int>(std::ceil(below * (rungs - 1))), 0, rungs - 1);
}

}  // namespace rgbdslam
