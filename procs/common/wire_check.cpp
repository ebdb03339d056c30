#include "common/wire_check.h"

#include <cstdint>
#include <string>

#include "common/protocol_limits.h"

namespace rgbdslam {
namespace {

using namespace limits;

// Reads the wire layout field by field; the first problem is kept and every later call
// does nothing, so a check reads as the message's field list.
class WireReader {
 public:
  WireReader(const void* data, size_t size, const char* type)
      : data_(static_cast<const uint8_t*>(data)), size_(size), type_(type) {}

  void fingerprint(int64_t expected) {
    if (!need(8, "fingerprint")) return;
    if (static_cast<int64_t>(bigEndian(8)) != expected) {
      fail("message does not decode as " + type_ + " (another type: its fingerprint differs)");
    }
  }
  // Fixed-size fields (numbers, fixed arrays): 'bytes' in all.
  void skip(size_t bytes, const char* field) { need(bytes, field); }
  // An int32 count or length: 0 <= n <= limit, else the message is rejected.
  int64_t count(const char* field, int64_t limit) {
    if (!need(4, field)) return 0;
    const auto n = static_cast<int32_t>(static_cast<uint32_t>(bigEndian(4)));
    if (n < 0 || n > limit) {
      fail(type_ + ": " + field + " is " + std::to_string(n) + ", outside [0, " + std::to_string(limit) + "]");
      return 0;
    }
    return n;
  }
  // n elements of element_bytes each, which must all be present.
  void array(int64_t n, size_t element_bytes, const char* field) {
    need(static_cast<size_t>(n) * element_bytes, field);  // n <= 2^31, element_bytes <= 64
  }
  // An LCM string: int32 length including the NUL (>= 1), the bytes, the NUL.
  void string(const char* field) {
    const int64_t length = count(field, kMaxStringBytes);
    if (!ok()) return;
    if (length < 1) return fail(type_ + ": string " + field + " has length 0 (it must count its NUL)");
    if (!need(static_cast<size_t>(length), field)) return;
    if (data_[pos_ - 1] != 0) fail(type_ + ": string " + field + " is not NUL-terminated");
  }
  Status finish() const {
    if (!ok()) return Error{error_};
    if (pos_ != size_) {
      return Error{"message has " + std::to_string(size_ - pos_) + " bytes beyond a " + type_ +
                   " (oversized or another type)"};
    }
    return Status{};
  }
  bool ok() const { return error_.empty(); }

 private:
  bool need(size_t bytes, const char* field) {
    if (!ok()) return false;
    if (bytes > size_ - pos_) {
      fail("message does not decode as " + type_ + " (truncated, or another type): " + field +
           " needs " + std::to_string(bytes) + " bytes at offset " + std::to_string(pos_) + ", " +
           std::to_string(size_ - pos_) + " are left");
      return false;
    }
    pos_ += bytes;
    return true;
  }
  uint64_t bigEndian(size_t bytes) const {  // the 'bytes' just consumed
    uint64_t value = 0;
    for (size_t i = pos_ - bytes; i < pos_; ++i) value = (value << 8) | data_[i];
    return value;
  }
  void fail(const std::string& what) {
    if (error_.empty()) error_ = what;
  }

  const uint8_t* data_;
  size_t size_, pos_ = 0;
  std::string type_, error_;
};

// Wire sizes of the nested structs (lcmtypes/*.lcm).
constexpr size_t kMeasurementBytes = 8 + 4 + 4 + 1 + 4;          // measurement_t
constexpr size_t kMapPointBytes = 8 + 3 * 4 + 8 + 4 + 4 + 1;     // map_point_t
constexpr size_t kKeyframePoseBytes = 8 + 3 * 8 + 4 * 8 + 8;      // keyframe_pose_t
constexpr size_t kPointPositionBytes = 8 + 3 * 4;                 // point_position_t
constexpr size_t kPoseBytes = 8 + 8 + 8 + 2 * (3 * 8 + 4 * 8) + 8 + 1 + 4 + 4 + 4;  // pose_t after the fingerprint

// An image field: format byte(s) already read; int32 size, then the bytes.
void imageBytes(WireReader& r, const char* size_field, const char* field) {
  r.array(r.count(size_field, kMaxImageBytes), 1, field);
}

}  // namespace

Status checkWire(const rgbdslam::rgbd_frame_t*, const void* data, size_t size) {
  WireReader r(data, size, rgbdslam::rgbd_frame_t::getTypeName());
  r.fingerprint(rgbdslam::rgbd_frame_t::getHash());
  r.skip(8 + 8 + 4 + 4 + 1, "utime, seq, width, height, colour_format");
  imageBytes(r, "colour_size", "colour");
  r.skip(1 + 4, "depth_format, depth_scale");
  imageBytes(r, "depth_size", "depth");
  r.string("camera_name");
  return r.finish();
}

Status checkWire(const rgbdslam::keyframe_t*, const void* data, size_t size) {
  WireReader r(data, size, rgbdslam::keyframe_t::getTypeName());
  r.fingerprint(rgbdslam::keyframe_t::getHash());
  r.skip(8 + 8 + 8 + 3 * 8 + 4 * 8 + 4 + 4 + 1,
         "utime, map_id, keyframe_id, position, orientation, width, height, grey_format");
  imageBytes(r, "grey_size", "grey");
  r.skip(1 + 4, "depth_format, depth_scale");
  imageBytes(r, "depth_size", "depth");
  r.array(r.count("num_measurements", kMaxKeyframePoints), kMeasurementBytes, "measurements");
  r.array(r.count("num_new_points", kMaxKeyframePoints), kMapPointBytes, "new_points");
  r.skip(1 + 8 + 3 * 8 + 4 * 8, "new_part, anchor_keyframe_id, anchor_position, anchor_orientation");
  return r.finish();
}

Status checkWire(const rgbdslam::map_t*, const void* data, size_t size) {
  WireReader r(data, size, rgbdslam::map_t::getTypeName());
  r.fingerprint(rgbdslam::map_t::getHash());
  r.skip(8 + 8 + 8 + 1 + 8, "utime, map_id, version, is_snapshot, acked_below");
  r.array(r.count("num_keyframes", kMaxMapKeyframes), kKeyframePoseBytes, "keyframes");
  r.array(r.count("num_points", kMaxMapPoints), kMapPointBytes, "points");
  r.array(r.count("num_moved", kMaxMapPoints), kPointPositionBytes, "moved");
  r.array(r.count("num_removed", kMaxMapPoints), 8, "removed_points");
  r.array(r.count("num_removed_keyframes", kMaxMapKeyframes), 8, "removed_keyframes");
  return r.finish();
}

Status checkWire(const rgbdslam::status_t*, const void* data, size_t size) {
  WireReader r(data, size, rgbdslam::status_t::getTypeName());
  r.fingerprint(rgbdslam::status_t::getHash());
  r.skip(8, "utime");
  r.string("component");
  r.string("state");
  const int64_t counters = r.count("num_counters", kMaxStatusEntries);
  for (int64_t i = 0; i < counters && r.ok(); ++i) r.string("counter_names");
  r.array(counters, 8, "counter_values");
  const int64_t timings = r.count("num_timings", kMaxStatusEntries);
  for (int64_t i = 0; i < timings && r.ok(); ++i) r.string("timing_names");
  r.array(timings, 4, "timing_values_ms");
  return r.finish();
}

Status checkWire(const rgbdslam::pose_t*, const void* data, size_t size) {
  WireReader r(data, size, rgbdslam::pose_t::getTypeName());
  r.fingerprint(rgbdslam::pose_t::getHash());
  r.skip(kPoseBytes, "pose fields");
  return r.finish();
}

Status checkWire(const rgbdslam::map_receipt_t*, const void* data, size_t size) {
  WireReader r(data, size, rgbdslam::map_receipt_t::getTypeName());
  r.fingerprint(rgbdslam::map_receipt_t::getHash());
  r.skip(7 * 8, "utime, map_id, applied_version, newest_version_seen, keyframes_created, keyframes_unacked, keyframes_sendable_from");
  return r.finish();
}

}  // namespace rgbdslam
