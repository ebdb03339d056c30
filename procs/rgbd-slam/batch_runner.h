#pragma once
// The rgbd-slam loop: read frames, run the SLAM system, write the trajectory, show
// progress, and at the end evaluate against ground truth when there is one.
#include <atomic>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/cli.h"
#include "common/frame_log.h"
#include "common/lcm_conversions.h"
#include "common/loss_report.h"
#include "common/slam_config.h"
#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/io/frame_source.h"
#include "rgbdslam/io/trajectory_io.h"
#include "rgbdslam/system/slam_system.h"

namespace rgbdslam {

struct BatchOptions {
  std::string source;
  std::string camera_path;                 // empty for synth: (the renderer's camera)
  std::string output;                      // trajectory file
  std::string frame_log;                   // per-frame CSV; empty: none
  bool deterministic = false;
  long max_frames = 0;                     // 0 = all
  bool quiet = false;
  std::string groundtruth_path;            // empty: the source's own
  SlamConfig config;                       // the SLAM options and their registry
  LinkOptions link;                        // deterministic: the simulated link (perfect by default)
  std::string save_map;                    // map file written at the end; empty: none
  std::string load_map;                    // map file to start from; empty: a new map
  bool localise_only = false;              // with load_map: add nothing to it
  // >= 0: keyframes reach the mapper encoded and decoded at this rung of rgbd-tracker's
  // encoding ladder (0: tracker_node.keyframe_*; higher: coarser, common/link_budget.h);
  // -1: as the tracker made them.
  int keyframe_rung = -1;
  KeyframeEncoding keyframe_encoding;      // that rung's encoding (keyframe_rung >= 0)

  static Expected<BatchOptions> fromCommandLine(const CommandLine& cli);
};

class BatchRunner {
 public:
  static Expected<std::unique_ptr<BatchRunner>> create(BatchOptions options);
  // Returns the exit status: 0 done, 1 frames were bad or the trajectory could not be written.
  int run(const std::atomic<bool>& stop);

 private:
  BatchRunner(BatchOptions options, PinholeCamera camera, std::unique_ptr<FrameSource> source,
              std::optional<Trajectory> groundtruth, const LoadedMap* start_map);
  bool saveMapIfAsked();
  KeyframeData throughWire(const KeyframeData& keyframe, const KeyframeEncoding& encoding);
  void printMapFileSummary() const;
  void showProgress(const TrackResult& result, bool final_line);
  void printSummary(const Trajectory& trajectory) const;

  BatchOptions options_;
  PinholeCamera camera_;
  std::unique_ptr<FrameSource> source_;
  std::optional<Trajectory> groundtruth_;
  std::unique_ptr<SlamSystem> slam_;
  std::vector<double> track_ms_;
  FrameLog frame_log_;  // open when --frame-log is given
  std::vector<TrackingState> pose_states_;       // the state of each trajectory pose
  std::map<TrackingState, long> state_frames_;  // frames per tracking state
  long inconsistent_frames_ = 0;  // frames whose first pose the depth image contradicted
  long depth_aided_frames_ = 0;   // frames whose pose depth held with too few points
  long new_parts_ = 0;            // frames that started a new part of the map (tracker.h)
  long rejoins_ = 0;              // ...and times the tracker went back to a part it had left
  Trajectory map_trajectory_;     // each posed frame's map pose (PoseEstimate::map_T_w_c)
  std::map<KeyframeId, Trajectory> part_trajectories_;  // map poses by the part tracked in
  // Each posed frame against the keyframe its pose rests on (TrackResult::anchor), for the
  // trajectory in the map as it ends (finalMapTrajectory).
  struct AnchoredPose {
    double t_s;
    KeyframeId anchor;  // -1: none
    SE3 T_anchor_c;
    KeyframeId part;
    SE3 map_T_w_c;
  };
  std::vector<AnchoredPose> anchored_;
  Trajectory finalMapTrajectory(long* left_out) const;
  double max_correction_m_ = 0.0;  // largest map correction not yet in the published pose [m]
  long bad_frames_ = 0;
  // Map files (printed only when --load-map or --save-map is given).
  double map_load_ms_ = 0.0, map_start_ms_ = 0.0, map_save_ms_ = 0.0;
  long map_saved_bytes_ = 0;
  long first_pose_frame_ = 0;    // frames read up to and including the first with a pose
  double first_pose_ms_ = -1.0;  // from the start of the run to that pose [ms]; -1: none
  // --keyframe-rung: what the link's codec sent.
  long wire_keyframes_ = 0, wire_bytes_ = 0, wire_errors_ = 0;
  LossReport loss_;  // logged even with --quiet: losing tracking is an event, not progress
};

}  // namespace rgbdslam
