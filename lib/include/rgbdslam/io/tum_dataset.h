#pragma once
// Reader for the TUM RGB-D benchmark layout: DIR/rgb.txt and DIR/depth.txt list
// "timestamp path" per line (paths relative to DIR; '#' starts a comment), colour is 8-bit
// PNG, depth 16-bit PNG in units of 1/depth_factor m (0 = no reading). Colour and depth are
// not synchronised: they are paired one-to-one by nearest timestamp within max_dt.
// Call order: openTumDataset() checks the lists and that every named file exists (fail
// fast, naming file and line: a missing or unreachable file, a symlink loop, a timestamp
// outside [0, kMaxTumTimestampS]); then next() decodes frame by frame. A frame that cannot be
// decoded (truncated PNG, 8-bit depth, wrong size) is reported as kBadFrame naming the file,
// and reading goes on with the next frame.
#include <memory>
#include <string>
#include <vector>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/io/frame_source.h"
#include "rgbdslam/util/expected.h"

namespace rgbdslam {

// Largest timestamp a list may hold: 1e10 s is the year 2286; in microseconds it stays far
// inside int64 (9.2e12 s), so frame stamps cannot overflow into negative times.
constexpr double kMaxTumTimestampS = 1e10;  // [s]

struct TumOptions {
  double max_dt_s = 0.02;  // largest |t_rgb - t_depth| for a pair [s]
  bool require_depth = true;  // false: colour frames without a depth partner are kept (depth empty)
};

struct TumEntry {
  double t_rgb = 0.0;    // [s]
  double t_depth = 0.0;  // [s]; NaN when there is no depth partner
  std::string rgb_path;
  std::string depth_path;  // empty when there is no depth partner
};

// Reads DIR/rgb.txt and DIR/depth.txt and associates them.
Expected<std::vector<TumEntry>> readTumIndex(const std::string& dir, const TumOptions& options);

class TumSource : public FrameSource {
 public:
  TumSource(std::string dir, std::vector<TumEntry> entries, PinholeCamera camera);
  FrameResult next() override;
  double nominalRateHz() const override;
  std::optional<size_t> size() const override { return entries_.size(); }
  std::string describe() const override;
  const std::vector<TumEntry>& entries() const { return entries_; }
  // Decodes entry i (no side effects; next() uses it).
  FrameResult read(size_t i) const;

 private:
  std::string dir_;
  std::vector<TumEntry> entries_;
  PinholeCamera camera_;
  size_t next_ = 0;
};

Expected<std::unique_ptr<TumSource>> openTumDataset(const std::string& dir,
                                                    const PinholeCamera& camera,
                                                    const TumOptions& options = {});

}  // namespace rgbdslam
