#pragma once
// The map protocol's options, one struct for both ends (section "sync" of config/slam.yaml):
// rgbd-tracker and rgbd-mapper read them from the same registry as the algorithms, and
// rgbd-slam runs both ends with them.
#include "rgbdslam/sync/keyframe_outbox.h"
#include "rgbdslam/sync/mapper_sync.h"
#include "rgbdslam/util/option_registry.h"

namespace rgbdslam {

struct SyncOptions {
  KeyframeOutboxOptions outbox;  // tracker: re-sends
  MapperSyncOptions mapper;      // mapper: intake queue and publisher
  double receipt_period_s = 1.0; // tracker: a map receipt this often [s]

  void bind(OptionRegistry* registry);  // section "sync"
};

}  // namespace rgbdslam
