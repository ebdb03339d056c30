#include "common/frame_log.h"

#include <cstdio>

namespace rgbdslam {

Expected<FrameLog> FrameLog::open(const std::string& path) {
  FrameLog log;
  log.out_.open(path);
  if (!log.out_) return Error{"cannot write --frame-log " + path};
  log.out_ << "seq,t_s,status,state,points,quality,sigma_m,sigma_deg,correction_m,depth_aided,inconsistent,"
              "keyframe,track_ms,after_pose_ms,latency_ms,reason\n";
  return log;
}

void FrameLog::write(const TrackResult& result, bool keyframe, const Times& times) {
  if (!out_.is_open()) return;
  static const char* const kStatus[] = {"initialised", "tracked", "lost", "relocalised", "bad_frame", "not_initialised"};
  const std::string& reason = result.status == TrackResult::Status::kBadFrame ? result.error : result.lost_reason;
  std::string quoted;  // CSV: in double quotes, a quote doubled
  for (char c : reason) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  char line[200];
  std::snprintf(line, sizeof(line), "%ld,%.6f,%s,%s,%d,%.3f,%.5f,%.4f,%.4f,%d,%d,%d,%.3f,", static_cast<long>(result.pose.seq),
                result.pose.utime * 1e-6, kStatus[static_cast<int>(result.status)], toString(result.pose.state),
                result.pose.points_tracked, result.pose.quality, result.pose_sigma_m, result.pose_sigma_deg,
                result.correction_m, result.depth_aided ? 1 : 0, result.inconsistent ? 1 : 0, keyframe ? 1 : 0,
                result.track_ms);
  out_ << line;
  for (const std::optional<double>& ms : {times.after_pose_ms, times.latency_ms}) {
    if (ms) {
      std::snprintf(line, sizeof(line), "%.3f", *ms);
      out_ << line;
    }
    out_ << ',';
  }
  out_ << '"' << quoted << "\"\n";
}

}  // namespace rgbdslam
