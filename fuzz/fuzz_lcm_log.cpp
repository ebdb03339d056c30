// libFuzzer target: an lcmlog: source, the LCM log reader and every frame on RGBD_FRAME
// through the wire check and the conversion, to the end of the log or its first error.
#include "common/lcm_log_source.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto source = rgbdslam::LcmLogSource::fromBytes(data, size, "RGBD_FRAME");
  if (!source) return 0;
  for (;;) {
    const rgbdslam::FrameResult result = (*source)->next();
    if (result.status == rgbdslam::FrameResult::Status::kEnd ||
        result.status == rgbdslam::FrameResult::Status::kFailed) {
      break;
    }
  }
  return 0;
}
