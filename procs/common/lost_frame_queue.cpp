#include "common/lost_frame_queue.h"

#include <algorithm>
#include <utility>

namespace rgbdslam {

LostFrameQueue::LostFrameQueue(int capacity) : slots_(static_cast<size_t>(std::max(0, capacity))) {}

void LostFrameQueue::offer(const RgbdFrame& frame) {
  if (frame.depth.empty() || frame.depth.type() != CV_16UC1) return;  // nothing to follow
  const long index = offered_++;
  if (slots_.empty() || index % stride_ != 0) return;
  if (size_ == slots_.size()) {
    // Full: slot j holds frame j * stride_; keep the even ones (frames 0, 2 stride_, ...).
    size_t kept = 0;
    for (size_t j = 0; j < size_; j += 2) std::swap(slots_[kept++], slots_[j]);
    size_ = kept;
    stride_ *= 2;
    if (index % stride_ != 0) return;
  }
  RgbdFrame& slot = slots_[size_++];
  frame.depth.copyTo(slot.depth);  // reuses the slot's buffer when the size matches
  slot.depth_scale = frame.depth_scale;
  slot.utime = frame.utime;
  slot.seq = frame.seq;
}

void LostFrameQueue::clear() {
  size_ = 0;
  offered_ = 0;
  stride_ = 1;
}

}  // namespace rgbdslam
