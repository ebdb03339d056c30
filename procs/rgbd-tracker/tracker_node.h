#pragma once
// rgbd-tracker's node: the onboard side of the map protocol (docs/design.md, "Map protocol").
// One thread, so the tracker needs no locks and a pose leaves as soon as it is computed:
//   RGBD_FRAME (local bus): frames are tracked in order from a backlog of at most
//   max_backlog_frames; when a newer frame arrives at a full backlog the oldest is skipped
//   and counted (a real-time tracker must not fall behind the camera: latency stays bounded
//   by the backlog, while one slow frame, e.g. a keyframe's, costs no pose). SLAM_POSE for
//   every tracked frame (its state says tracking / dodgy / lost / relocalised /
//   initialising). A new keyframe (with provisional
//   points from depth, tracked against at once) is published on SLAM_KEYFRAME (link) and
//   kept until a map message acknowledges it; an unacknowledged keyframe is re-sent after
//   resend_period_s, then after twice that, and so on up to resend_max_period_s (a slow
//   mapper is not flooded with copies), oldest first, at most resend_max at a time.
//   SLAM_MAP (link): the acknowledgements are taken from every message of this map; the
//   content is applied only when it is newer (the tracker never goes backwards; a delta
//   after a lost one waits for the next snapshot).
//   SLAM_STATUS (link) every status_period_s: state, counters, timings, queue lengths.
// Two LCM instances when the link has its own URL (frames never cross the radio link).
#include <atomic>
#include <chrono>
#include <lcm/lcm-cpp.hpp>
#include <deque>
#include <map>
#include <memory>
#include <string>

#include "common/lcm_conversions.h"
#include "common/loss_report.h"
#include "common/samples.h"
#include "rgbdslam/tracking/tracker.h"

namespace rgbdslam {

struct TrackerNodeOptions {
  std::string frame_channel = "RGBD_FRAME";
  std::string pose_channel = "SLAM_POSE";
  std::string keyframe_channel = "SLAM_KEYFRAME";
  std::string map_channel = "SLAM_MAP";
  std::string status_channel = "SLAM_STATUS";
  double resend_period_s = 1.0;   // an unacknowledged keyframe is first re-sent after this [s]
  double resend_max_period_s = 4.0;  // the doubling re-send interval stops growing here [s]
  int resend_max = 2;             // keyframes re-sent at one time at most (oldest first)
  int max_backlog_frames = 2;     // frames waiting to be tracked at most; older ones skipped
  double status_period_s = 1.0;   // SLAM_STATUS period [s]
  double exit_after_idle_s = 0;   // after frames stop for this long, finish; 0 = never [s]
  double ack_wait_s = 10;         // when finishing, wait this long for acknowledgements [s]
  KeyframeEncoding encoding{/*jpeg_grey=*/true, /*jpeg_quality=*/75, /*depth_step=*/4};
};

class TrackerNode {
 public:
  // 'link' may be the same instance as 'local'.
  TrackerNode(lcm::LCM* local, lcm::LCM* link, const PinholeCamera& camera,
              const TrackerOptions& tracker_options, SlamMode mode, int64_t map_id,
              TrackerNodeOptions options);
  // Runs until 'stop', or (exit_after_idle_s) until frames stopped and every keyframe is
  // acknowledged or ack_wait_s passed. Returns the exit status: 0, or 1 when keyframes
  // were left unacknowledged.
  int run(const std::atomic<bool>& stop);
  void printSummary() const;

 private:
  using Clock = std::chrono::steady_clock;
  void onFrame(const lcm::ReceiveBuffer* buffer, const std::string& channel);
  struct Received;
  void trackFrame(const Received& received);
  void onMap(const lcm::ReceiveBuffer* buffer, const std::string& channel);
  void sendKeyframe(const KeyframeData& keyframe);
  void resendDue(Clock::time_point now);
  void publishStatus();
  void handleAvailable(int timeout_ms);

  lcm::LCM* local_;
  lcm::LCM* link_;
  TrackerNodeOptions options_;
  Tracker tracker_;
  int64_t map_id_;

  struct Outgoing {
    std::vector<uint8_t> bytes;  // the encoded keyframe_t
    Clock::time_point created, next_send;
    double interval_s = 0;  // until the next re-send [s]
    int sends = 0;
  };
  std::map<KeyframeId, Outgoing> unacked_;
  std::map<KeyframeId, Clock::time_point> created_;  // keyframes not yet in an applied map
  struct Received {
    std::vector<uint8_t> bytes;
    int64_t recv_utime = 0;  // when LCM received it [us]
  };
  std::deque<Received> backlog_;  // frames received, not yet tracked, oldest first
  Clock::time_point last_frame_{}, last_status_{};
  TrackingState state_ = TrackingState::kInitialising;
  // latency (frame utime to its pose's publication) = arrival (utime to the message's
  // receipt: capture's encoding and LCM's transfer) + frame time (receipt to publication:
  // the tracker's own time per frame: backlog, decoding, tracking, publishing).
  RecentSamples track_ms_, latency_ms_, arrival_ms_, frame_ms_, ack_ms_, in_map_ms_;

  struct Counters {
    long frames = 0, frames_skipped = 0, poses = 0, lost = 0, bad_frames = 0, bad_frame_messages = 0,
         bad_map_messages = 0, keyframes = 0, keyframe_sends = 0, keyframes_acked = 0,
         maps_received = 0, maps_applied = 0, maps_stale = 0, maps_foreign = 0,
         maps_missing_delta = 0, maps_unknown_keyframe = 0, keyframe_bytes = 0;
  };
  Counters counters_;
  LossReport loss_;  // logs losing tracking and relocalising, one line each
  int64_t newest_version_seen_ = 0;  // of this map, applied or not
};

}  // namespace rgbdslam
