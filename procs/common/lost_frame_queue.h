#pragma once
// The depth of lost frames rgbd-tracker passes while its relocaliser thread holds the
// tracker, kept for the dead reckoning to follow before the next relocalisation
// (Tracker::followLost; docs/design.md, "Dead reckoning by depth while lost").
//
// Why: off the frame path (tracker_node.relocalise_off_frame_path) the tracker saw only the
// frames relocalised; a relocalisation takes about a frame's time on an idle machine and
// two to three beside a loaded one (the 10-minute flight through the suite: 24 and 86 ms
// at the median), and the dead reckoning's steps between the frames it saw were that much
// longer. Emulated in batch on the 10-minute flight's first 4400 frames, following only
// every 3rd lost frame started the three new parts 1.11, 0.63 and 1.14 m off, against
// 0.50, 0.34 and 0.72 m following every frame (docs/open_work.md, session 39). Through
// the suite, though, following the passed frames made the parts' headings worse after two
// of the turns taken while lost: off by default (tracker_node.follow_passed_frames;
// process_options.h).
//
// At most 'capacity' frames, evenly spaced over those offered: every frame until full, then
// every 2nd (every other one kept is dropped), every 4th, and so on; the longer the
// relocalisation, the sparser. The last frames offered may fall between the kept ones (6
// offered to 3 slots keep the 1st and 5th): the frame relocalised next follows them within
// a few frames anyway. Only the depth, its scale and the time are kept, in buffers reused
// from one relocalisation to the next (no allocation once each slot has held a frame of the
// camera's size); a frame without 16-bit depth is not offered at all.
#include <cstddef>
#include <vector>

#include "rgbdslam/image/rgbd_frame.h"

namespace rgbdslam {

class LostFrameQueue {
 public:
  explicit LostFrameQueue(int capacity);
  // A frame passed: kept if it is its turn (a copy of its depth, depth_scale and utime);
  // ignored without 16-bit depth.
  void offer(const RgbdFrame& frame);
  // The frames kept, oldest first: frame(0) .. frame(size() - 1).
  size_t size() const { return size_; }
  const RgbdFrame& frame(size_t i) const { return slots_[i]; }
  // Forgets the frames kept (the buffers stay); the next offered is kept.
  void clear();
  // Frames offered since the last clear() (those with 16-bit depth).
  long offered() const { return offered_; }

 private:
  std::vector<RgbdFrame> slots_;  // 'capacity' slots; the first size_ hold frames
  size_t size_ = 0;
  long offered_ = 0;
  long stride_ = 1;  // every stride_-th frame offered is kept
};

}  // namespace rgbdslam
