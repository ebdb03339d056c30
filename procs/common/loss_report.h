#pragma once
// Losing tracking and getting it back are events an operator must see: LossReport turns the
// stream of TrackResults into one line at each transition and counts the episodes, for
// rgbd-slam and rgbd-tracker alike.
#include <string>

#include "rgbdslam/tracking/tracker.h"

namespace rgbdslam {

class LossReport {
 public:
  // Feeds one frame's result; returns the line to log ("" when nothing changed). A bad
  // frame changes nothing.
  std::string update(const TrackResult& result);

  long episodes() const { return episodes_; }              // times tracking was lost
  long relocalisations() const { return relocalisations_; }  // times it came back
  bool lost() const { return lost_since_seq_ >= 0; }
  long lostSinceSeq() const { return lost_since_seq_; }    // seq of the losing frame; -1

 private:
  long lost_since_seq_ = -1;
  long lost_run_ = 0;  // frames lost since then
  long episodes_ = 0;
  long relocalisations_ = 0;
};

}  // namespace rgbdslam
