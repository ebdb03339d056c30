#pragma once
// rgbd-tracker's node: the onboard tracker, converting messages for the tracker's end of the
// map protocol (lib sync/tracker_sync.h, docs/design.md "Map protocol").
// One thread for tracking and LCM, so the tracker needs no locks and a pose leaves as soon as it is computed
// (while lost, a second holds the tracker in turn: "Relocalisation leaves the frame path" below):
//   RGBD_FRAME (local bus): frames are tracked in order from a backlog of at most
//   max_backlog_frames; when a newer frame arrives at a full backlog the oldest is skipped
//   and counted (a real-time tracker must not fall behind the camera: latency stays bounded
//   by the backlog, while one slow frame, e.g. a keyframe's, costs no pose); while lost and
//   relocalising in line (relocalise_off_frame_path false), a frame with a newer one waiting
//   is passed unrelocalised (Tracker::passLost). SLAM_POSE for
//   every tracked frame (its state says tracking / dodgy / lost / relocalised /
//   initialising), as soon as the pose is known: the frame's keyframe and local map follow
//   it (Tracker::trackPose, finishFrame; issue 10, item 6).
//   Relocalisation leaves the frame path too (tracker_node.relocalise_off_frame_path): a
//   lost frame is relocalised on a second thread, which holds the tracker until this
//   thread takes the outcome; meanwhile this thread answers every frame lost at once (the
//   one being relocalised first), holds map versions back (applied before the next
//   relocalisation starts) and reads nothing of the tracker but its camera (frameError).
//   The frames passed meanwhile are counted to the tracker afterwards, and the depth of up
//   to follow_passed_frames of them is kept for the next relocalisation's job to follow by
//   dead reckoning first (Tracker::followLost; common/lost_frame_queue.h).
//   The first pose of a run (in a loaded map too) is always found in line. A relocalisation that worked publishes no pose of its own (its frame was
//   answered already): the next frame is tracked from it. Why: a relocalisation takes
//   6-12 tracked frames' time on a large map (the 10-minute flight: 17 ms median, 35 ms
//   p99, against 2.8 ms), and its frames made the p99 of the frame-to-pose latency; a
//   flight controller is better served by a prompt "lost" than by a stale pose, and the
//   next frame's pose follows within a frame's time (docs/design.md, "Threads").
//   SLAM_KEYFRAME (link): a new keyframe is encoded once, at the rung of the encoding ladder
//   the link budget allows (common/link_budget.h), on a second thread (the encoder: JPEG,
//   zlib and LCM encoding leave the frame path, issue 10 item 6; this thread publishes it
//   when it is done, in creation order, polling every 1 ms meanwhile), and handed to
//   TrackerSync when it goes out, which keeps it and says when to re-send it until a map
//   message acknowledges it. No keyframe waits for the budget.
//   SLAM_MAP (link): decoded when it arrives, applied when no frame waits (a frame does not
//   wait for a map update) or after 100 ms; TrackerSync takes the acknowledgements and
//   says whether the content is applied to the replica.
//   SLAM_MAP_RECEIPT (link) every sync receipt period: the version the tracker holds.
//   SLAM_STATUS (link) every status_period_s: state, counters, timings, queue lengths.
// Two LCM instances when the link has its own URL (frames never cross the radio link).
#include <array>
#include <atomic>
#include <chrono>
#include <lcm/lcm-cpp.hpp>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "common/frame_log.h"
#include "common/lcm_conversions.h"
#include "common/link_budget.h"
#include "rgbdslam/util/background_worker.h"
#include "common/loss_report.h"
#include "common/lost_frame_queue.h"
#include "common/process_options.h"
#include "common/samples.h"
#include "common/store_spill.h"
#include "rgbdslam/map/map_file.h"
#include "rgbdslam/sync/sync_options.h"
#include "rgbdslam/sync/tracker_sync.h"
#include "rgbdslam/tracking/tracker.h"

namespace rgbdslam {

struct TrackerNodeOptions {
  ChannelOptions channels;        // config section "channels"
  TrackerProcessOptions process;  // config section "tracker_node"
  SyncOptions sync;               // config section "sync": re-sends, receipt period
};

class TrackerNode {
 public:
  // 'link' may be the same instance as 'local'.
  TrackerNode(lcm::LCM* local, lcm::LCM* link, const PinholeCamera& camera,
              const TrackerOptions& tracker_options, SlamMode mode, int64_t map_id,
              TrackerNodeOptions options);
  // Before run(): start from a map file's content (rgbd-tracker --load-map), as the mapper
  // does with the same file and map id: keyframe ids continue after the file's. With
  // 'localise_only' the tracker adds no keyframes (tracker.h, load).
  void startFrom(const LoadedMap& map, bool localise_only);
  // Before run(): write one line per frame tracked to 'log' (rgbd-tracker --frame-log).
  void logFramesTo(FrameLog log) { frame_log_ = std::move(log); }
  // Ok, or why the keyframe store the options asked for could not be made.
  const Status& keyframeStoreStatus() const { return tracker_.keyframeStoreStatus(); }
  const KeyframeStore* keyframeStore() const { return tracker_.keyframeStore(); }
  // Runs until 'stop', or (exit_after_idle_s) until frames stopped and every keyframe is
  // acknowledged or ack_wait_s passed. Returns the exit status: 0, or 1 when keyframes
  // were left unacknowledged.
  int run(const std::atomic<bool>& stop);
  void printSummary() const;
  // Keyframes made and acknowledged (a keyframe the mapper lost and got again counts once;
  // one lost from the outbox's storage does not count).
  long keyframesAcked() const {
    return counters_.keyframes - static_cast<long>(keyframesUnacked()) - static_cast<long>(sync_.outbox().spillErrors());
  }
  // Sent and not yet acknowledged, waiting for the budget, or being encoded.
  size_t keyframesUnacked() const { return sync_.outbox().size() + encoding_.size(); }

 private:
  using Clock = std::chrono::steady_clock;
  void onFrame(const lcm::ReceiveBuffer* buffer, const std::string& channel);
  struct Received;
  void trackFrame(const Received& received);
  void onMap(const lcm::ReceiveBuffer* buffer, const std::string& channel);
  void applyMap(const MapUpdate& update);  // a received version: the protocol, the replica
  void applyOldestMap();                   // of pending_maps_
  void sendKeyframe(KeyframeData keyframe);
  void sendEncoded(Clock::time_point now);
  void publishKeyframe(KeyframeId id, std::vector<uint8_t> bytes, Clock::time_point now);  // first send
  void publishKeyframeBytes(const std::vector<uint8_t>& bytes);  // any send: link, budget, counters
  void resendDue();
  void publishReceipt();
  void publishStatus();
  void handleAvailable(int timeout_ms);
  // Waits up to timeout_ms for a message on either LCM socket; which have one, in 'readable'
  // (may be null).
  bool pollSockets(int timeout_ms, std::array<bool, 2>* readable) const;
  // Relocalisation off the frame path: startRelocalisation() hands frame_ (swapped out,
  // so the next frame decodes into other buffers) and tracker_ to relocaliser_;
  // collectRelocalisation() takes the outcome when it is done, or waits for it ('wait'),
  // and gives the tracker back to this thread.
  void startRelocalisation();
  void collectRelocalisation(bool wait);
  bool relocalising() const { return relocalisation_.valid(); }
  // A frame answered lost without the tracker (its frame check aside): the last published pose.
  TrackResult answerLost(const RgbdFrame& frame, const std::string& reason) const;
  // What the status reports of the tracker's map and store, read while this thread holds
  // the tracker; while the relocaliser does, the status reports the last read.
  struct TrackerFigures {
    int64_t points = 0, points_on_storage = 0, points_lost_on_storage = 0, keyframes_hot = 0, store_entries = 0, store_kb = 0, store_disk_kb = 0, store_errors = 0;
  };
  void readTrackerFigures();
  TrackerFigures tracker_figures_;

  lcm::LCM* local_;
  lcm::LCM* link_;
  TrackerNodeOptions options_;
  Tracker tracker_;
  int64_t map_id_;

  // Unacknowledged keyframes beyond sync.unacked_in_memory (common/store_spill.h); before
  // sync_, which drops what it spilled when it goes.
  std::unique_ptr<KeyframeStore> outbox_store_;
  std::unique_ptr<StoreSpill> outbox_spill_;
  TrackerSync<std::vector<uint8_t>> sync_;  // the encoded keyframe_t of each unacknowledged keyframe
  std::map<KeyframeId, Clock::time_point> created_;  // keyframes not yet in an applied map
  LinkBudget budget_;
  std::vector<KeyframeEncoding> ladder_;  // keyframe encodings, best first
  struct Encoded {
    std::vector<uint8_t> bytes;  // the keyframe_t message
    double ms = 0;               // time on the encoder thread [ms]
  };
  struct Encoding {
    KeyframeId id;
    std::shared_future<Encoded> encoded;
  };
  std::deque<Encoding> encoding_;  // keyframes on the encoder thread, oldest first
  BackgroundWorker encoder_;       // its jobs own their keyframe and encoding; they touch no member
  struct Received {
    std::vector<uint8_t> bytes;
    int64_t recv_utime = 0;  // when LCM received it [us]
  };
  std::deque<Received> backlog_;  // frames received, not yet tracked, oldest first
  // Buffers kept from frame to frame, so that a frame allocates nothing (common/lcm_conversions.h,
  // decodeFrame): received bytes of frames tracked or skipped, the decoded message, the frame.
  std::vector<std::vector<uint8_t>> spare_bytes_;
  rgbdslam::rgbd_frame_t frame_msg_;
  RgbdFrame frame_;
  void recycle(std::vector<uint8_t>&& bytes);
  struct PendingMap {
    MapUpdate update;
    Clock::time_point received;
  };
  std::deque<PendingMap> pending_maps_;  // map versions decoded, not yet applied, oldest first
  Clock::time_point last_frame_{}, last_status_{}, last_receipt_{};
  TrackingState state_ = TrackingState::kInitialising;
  // latency (frame utime to its pose's publication) = arrival (utime to the message's
  // receipt: capture's encoding and LCM's transfer) + frame time (receipt to publication:
  // the tracker's own time per frame: backlog, decoding, tracking, publishing).
  RecentSamples track_ms_, latency_ms_, arrival_ms_, frame_ms_, ack_ms_, in_map_ms_;
  RecentSamples encode_ms_;  // a keyframe's encoding on the encoder thread, off the frame path
  // Work between frames on this thread, after the pose is out: a frame's keyframe and
  // local map (Tracker::finishFrame), and applying a map version to the replica.
  RecentSamples after_pose_ms_, map_apply_ms_;
  RecentSamples map_deferred_ms_;   // each step of a map version's work held back
  bool deferred_map_work_ = false;  // a map version's work on cold keyframes is left

  struct Counters {
    long frames = 0, frames_skipped = 0, frames_passed = 0, poses = 0, lost = 0, bad_frames = 0, bad_frame_messages = 0,
         bad_map_messages = 0, keyframes = 0, keyframe_sends = 0, inconsistent = 0, depth_aided = 0,
         new_parts = 0,  // frames that started a new part of the map (tracker.h)
         maps_received = 0, maps_applied = 0, maps_stale = 0, maps_foreign = 0,
         maps_missing_delta = 0, maps_unknown_keyframe = 0, maps_implausible = 0, keyframe_bytes = 0,
         keyframes_coarser = 0,     // sent below the best rung of the ladder
         keyframes_over_budget = 0; // sent while the bucket was empty (link_budget.h)
    int last_rung = 0;
  };
  Counters counters_;
  // The job on relocaliser_ (valid while one runs), its frame and what it left: its frame
  // and outcome belong to the job until collectRelocalisation().
  std::shared_future<void> relocalisation_;
  RgbdFrame relocalising_frame_;
  TrackResult relocalised_;
  std::optional<KeyframeData> relocalised_keyframe_;  // finishFrame()'s, if any
  int frames_while_relocalising_ = 0;  // answered lost meanwhile
  // Frames passed while relocalising, for the next job to follow by depth first
  // (Tracker::followLost). Handed over by following_: this thread offers frames only while
  // it is false; set when a job starts with frames to follow, cleared by the job once it
  // has followed them (frames that come meanwhile are not kept: one set of buffers, not
  // two; following took 21.6 ms at the p99 in a 2-minute flight beside a compile).
  LostFrameQueue passed_;
  std::atomic<bool> following_{false};
  long frames_followed_ = 0;  // handed to followLost, over the run
  double followed_ms_ = -1.0;  // the job's time following them; < 0: none (read after it ends)
  RecentSamples follow_ms_;    // of the jobs that followed frames [ms]
  long relocalisations_started_ = 0, relocalisations_recovered_ = 0;
  RecentSamples relocalise_ms_;  // the job's trackPose() [ms]
  PoseEstimate last_published_;  // its poses and part are what answerLost() publishes
  LossReport loss_;  // logs losing tracking and relocalising, one line each
  FrameLog frame_log_;  // --frame-log: one line per frame tracked (closed: none)
  std::array<long, 5> state_frames_{};  // frames per TrackingState (by its value)
  // Relocalises off the frame path; last, so that its job (which uses tracker_) is joined
  // before anything else goes.
  BackgroundWorker relocaliser_;
};

}  // namespace rgbdslam
