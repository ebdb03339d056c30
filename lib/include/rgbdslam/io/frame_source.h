#pragma once
// A source of RGB-D frames: a TUM directory, the synthetic renderer (both in lib/io), or,
// in procs/common, an OpenNI2 device or an LCM log. Call order: construct (fails fast on
// bad input), then next() until it returns End.
#include <memory>
#include <optional>
#include <string>

#include "rgbdslam/image/rgbd_frame.h"

namespace rgbdslam {

struct FrameResult {
  enum class Status {
    kFrame,     // 'frame' holds the next frame
    kBadFrame,  // this frame could not be read; 'error' says why; later frames may be fine
    kEnd,       // no more frames
    kFailed,    // the source failed for good (device unplugged, ...); 'error' says why
  };
  Status status = Status::kEnd;
  RgbdFrame frame;
  std::string error;
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual FrameResult next() = 0;
  // Rate the frames were recorded at [Hz], for pacing replay; 0 if unknown/live.
  virtual double nominalRateHz() const = 0;
  // Number of frames if known in advance, else nullopt (live devices).
  virtual std::optional<size_t> size() const = 0;
  // One line for logs, e.g. "tum:/data/seq (795 frames)".
  virtual std::string describe() const = 0;
};

}  // namespace rgbdslam
