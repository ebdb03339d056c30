#pragma once
// The processes' own options, in the same registry (and config/slam.yaml) as the algorithms':
// the LCM channels every process agrees on (section "channels"), and what only rgbd-tracker
// ("tracker_node") or rgbd-mapper ("mapper_node") uses. Defaults are the in-class
// initialisers below and nowhere else; rgbd-capture and pose-logger take their one channel's
// default from ChannelOptions too. What names one run rather than configures the suite (the
// camera file, LCM URLs, the map id, the state folder) stays on the command line.
#include <string>

#include "common/lcm_conversions.h"
#include "common/link_budget.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct ChannelOptions {
  std::string frame = "RGBD_FRAME";            // frames (local bus)
  std::string pose = "SLAM_POSE";              // poses (local bus)
  std::string keyframe = "SLAM_KEYFRAME";      // keyframes to the mapper (link)
  std::string map = "SLAM_MAP";                // maps to the tracker (link)
  std::string receipt = "SLAM_MAP_RECEIPT";    // the tracker's map receipts (link)
  std::string tracker_status = "SLAM_STATUS";  // the tracker's health (link)
  std::string mapper_status = "MAPPER_STATUS"; // the mapper's health
  void bind(OptionRegistry* registry);
};

struct TrackerProcessOptions {
  double status_period_s = 1.0;  // [s]
  int max_backlog_frames = 2;    // [frames]
  double exit_after_idle_s = 0;  // 0: run until stopped [s]
  double ack_wait_s = 10;        // [s]
  // Keyframes on the link: JPEG grey, depth at every 4th pixel and row.
  KeyframeEncoding keyframe_encoding{/*jpeg_grey=*/true, /*jpeg_quality=*/75, /*depth_step=*/4};
  LinkBudgetOptions link_budget;  // the best rung is keyframe_encoding (common/link_budget.h)
  void bind(OptionRegistry* registry);
};

struct MapperProcessOptions {
  double status_period_s = 1.0;  // [s]
  void bind(OptionRegistry* registry);
};

struct ProcessOptions {
  ChannelOptions channels;
  TrackerProcessOptions tracker_node;
  MapperProcessOptions mapper_node;
  void bind(OptionRegistry* registry);
};

}  // namespace rgbdslam
