#include "common/loss_report.h"

#include <cstdio>

namespace rgbdslam {

std::string LossReport::update(const TrackResult& result) {
  using Status = TrackResult::Status;
  const long seq = static_cast<long>(result.pose.seq);
  char line[200] = "";
  if (result.status == Status::kLost) {
    if (lost_since_seq_ < 0) {
      lost_since_seq_ = seq;
      ++episodes_;
      std::snprintf(line, sizeof(line), "frame %ld: tracking lost (%s; %d points found, quality %.2f); relocalising",
                    seq, result.lost_reason.empty() ? "no pose" : result.lost_reason.c_str(),
                    result.pose.points_tracked, result.pose.quality);
    }
    ++lost_run_;
  } else if (result.status == Status::kRelocalised) {
    ++relocalisations_;
    if (lost_since_seq_ < 0) {  // no loss before: a tracker started lost, in a loaded map
      std::snprintf(line, sizeof(line), "frame %ld: localised in the loaded map (%d points found)", seq,
                    result.pose.points_tracked);
    } else {
      std::snprintf(line, sizeof(line), "frame %ld: relocalised after %ld lost frames (lost at frame %ld, %d points found)",
                    seq, lost_run_, lost_since_seq_, result.pose.points_tracked);
    }
    lost_since_seq_ = -1, lost_run_ = 0;
  } else if (result.new_part) {
    std::snprintf(line, sizeof(line),
                  "frame %ld: a new part of the map started after %ld lost frames (lost at frame %ld, %d points "
                  "from depth), %s",
                  seq, lost_run_, lost_since_seq_, result.pose.points_tracked,
                  result.part_start_reckoned ? "where depth followed the camera" : "where the camera coasted to");
    lost_since_seq_ = -1, lost_run_ = 0;
  } else if (result.status == Status::kTracked || result.status == Status::kInitialised) {
    lost_since_seq_ = -1, lost_run_ = 0;
  }
  return line;
}

}  // namespace rgbdslam
