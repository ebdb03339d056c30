#pragma once
// Conversions between the library's plain types and the LCM messages (lcmtypes/).
// Handlers call only these: decodeMessage<T>() checks the wire layout before liblcm decodes
// (wire_check.h), then fromLcm() checks every field's range (protocol_limits.h): sizes that
// match, formats, finite values, ids >= 0, pyramid levels < kMaxLevels, pixels inside the
// image, unit quaternions, positions and depths within the world bound. Each returns an
// error naming the field instead of trusting the message.
#include <limits>
#include <stdexcept>
#include <string>

#include <rgbdslam/keyframe_t.hpp>
#include <rgbdslam/map_receipt_t.hpp>
#include <rgbdslam/map_t.hpp>
#include <rgbdslam/pose_t.hpp>
#include <rgbdslam/rgbd_frame_t.hpp>
#include <rgbdslam/status_t.hpp>

#include "rgbdslam/image/rgbd_frame.h"
#include "rgbdslam/map/map_types.h"
#include "rgbdslam/tracking/pose_estimate.h"
#include "rgbdslam/util/component_status.h"
#include "rgbdslam/util/expected.h"
#include "common/wire_check.h"

namespace rgbdslam {

// How frames are encoded on the wire.
struct FrameEncoding {
  bool jpeg_colour = false;  // false: raw BGR (lossless); true: JPEG
  int jpeg_quality = 90;     // JPEG quality [1, 100]
  bool zlib_depth = true;    // true: zlib-compressed depth (lossless); false: raw
  int zlib_level = 1;        // zlib level [0, 9]; 1 is fastest with most of the gain
};

rgbdslam::rgbd_frame_t toLcm(const RgbdFrame& frame, const FrameEncoding& encoding);
Expected<RgbdFrame> fromLcm(const rgbdslam::rgbd_frame_t& msg);
// The same into 'frame', reusing its images' buffers where they have the size and nothing
// else holds them (a keyframe made from the frame before keeps its own: a new buffer is made
// then). On an error 'frame' is left in an unspecified state.
Status fromLcm(const rgbdslam::rgbd_frame_t& msg, RgbdFrame* frame);

// A pose as it travels: the estimate and the map it is expressed in (keyframe_t.map_id), so
// a listener can keep two trackers on one bus apart.
struct MapPose {
  int64_t map_id = 0;
  PoseEstimate pose;
};
rgbdslam::pose_t toLcm(const PoseEstimate& pose, int64_t map_id);
Expected<MapPose> fromLcm(const rgbdslam::pose_t& msg);

// How keyframes are encoded on the wire. The default is lossless (what tests compare); the
// tracker process sends JPEG grey and half-resolution depth by default to keep the radio link
// under 1 Mbit/s (see docs/design.md, "What crosses the link").
struct KeyframeEncoding {
  bool jpeg_grey = false;   // false: PNG (lossless); true: JPEG
  int jpeg_quality = 90;    // JPEG quality [1, 100]
  int depth_step = 1;       // depth at every n-th pixel and row: 1 (all), 2 (DEPTH_*_HALF),
                            // 4 (DEPTH_*_QUARTER) or 8 (DEPTH_*_EIGHTH)
  // > 0: depth as quantised inverse depth in steps of this [1/m] (DEPTH_INVERSE_ZSTD*,
  // image/codec.h); 0: zlib, lossless.
  double inverse_depth_step = 0.0;
  // Depth only in the blocks a FAST corner of the grey image reaches (cornerBlockMask;
  // corners a little below the default thresholds, lcm_conversions.cpp), no reading
  // elsewhere: all the mapper reads; the whole depth where that is no larger. A corridor
  // frame at the quarter step: 6.6 -> 4.1 kB.
  bool depth_near_corners = false;
};
rgbdslam::keyframe_t toLcm(const KeyframeData& keyframe, const KeyframeEncoding& encoding = {});
Expected<KeyframeData> fromLcm(const rgbdslam::keyframe_t& msg);

rgbdslam::map_t toLcm(const MapUpdate& update);
Expected<MapUpdate> fromLcm(const rgbdslam::map_t& msg);

rgbdslam::map_receipt_t toLcm(const MapReceipt& receipt);
Expected<MapReceipt> fromLcm(const rgbdslam::map_receipt_t& msg);

rgbdslam::status_t toLcm(const ComponentStatus& status);
Expected<ComponentStatus> fromLcm(const rgbdslam::status_t& msg);

// Decodes raw bytes as message type T. The wire check (wire_check.h) runs first: it rejects
// truncated data, trailing bytes (oversized or a different type with a matching prefix), a
// wrong type fingerprint, and counts or lengths that are negative, beyond the protocol's
// limits or not backed by bytes, before liblcm's decoder allocates anything.
// Into an existing message: its arrays keep their capacity (no allocation when the message
// is no larger than the one before). The caller empties the arrays first: liblcm leaves an
// array whose count is 0 as it was.
template <typename T>
Status decodeMessage(const void* data, size_t size, T* msg) {
  if (size > static_cast<size_t>(std::numeric_limits<int>::max())) {
    return Error{"message of " + std::to_string(size) + " bytes is too large"};
  }
  if (Status wire = checkWire<T>(data, size); !wire) return Error{wire.error()};
  int used = -1;
  try {
    used = msg->decode(data, 0, static_cast<int>(size));
  } catch (const std::exception& e) {  // not expected after the wire check; kept as a backstop
    return Error{"message does not decode as " + std::string(T::getTypeName()) + " (" + e.what() + ")"};
  }
  if (used < 0 || static_cast<size_t>(used) != size) {
    return Error{"message does not decode as " + std::string(T::getTypeName()) + ", " +
                 std::to_string(size) + " bytes"};
  }
  return Status{};
}

template <typename T>
Expected<T> decodeMessage(const void* data, size_t size) {
  T msg;
  if (Status decoded = decodeMessage(data, size, &msg); !decoded) return Error{decoded.error()};
  return msg;
}

// A frame at the camera's rate, decoded with the buffers of the one before: 'msg' and
// 'frame' are the caller's, kept from frame to frame (rgbd-tracker). Why: a 640x480 frame is
// 1.5 MB, and fresh buffers for its message and images (4.6 MB a frame) are either new
// mappings, page faults (with glibc's mmap threshold fixed at 128 kB the corridor's median
// latency was 5.0 ms with fresh buffers, 3.8 ms with these; 2.9 ms with glibc's default;
// docs/open_work.md, session 24), or blocks that churn the heap.
Status decodeFrame(const void* data, size_t size, rgbdslam::rgbd_frame_t* msg, RgbdFrame* frame);

}  // namespace rgbdslam
