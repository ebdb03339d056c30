#pragma once
// Walks a message's LCM wire layout before liblcm decodes it. liblcm 1.3.1's generated
// decoders trust the counts a message claims: they allocate and zero arrays sized from the
// header before checking that the bytes are there, and compute an array's byte size in a
// 32-bit int (lcm_coretypes.h), so a 110-byte map claiming 2^28 ids reads past the buffer.
// checkWire<T>() instead checks every count and string length: >= 0, within the protocol's
// limit (protocol_limits.h), and backed by bytes actually present, then that the message
// ends exactly where the layout does. Only then may decode() run (decodeMessage<T> does so).
// Layout (lcmtypes/*.lcm): the 8-byte type fingerprint, then the fields in order, big-endian;
// nested structs without a fingerprint; a string is an int32 length including the NUL, then
// the bytes and the NUL.
#include <cstddef>

#include <rgbdslam/keyframe_t.hpp>
#include <rgbdslam/map_receipt_t.hpp>
#include <rgbdslam/map_t.hpp>
#include <rgbdslam/pose_t.hpp>
#include <rgbdslam/rgbd_frame_t.hpp>
#include <rgbdslam/status_t.hpp>

#include "rgbdslam/util/expected.h"

namespace rgbdslam {

Status checkWire(const rgbdslam::rgbd_frame_t*, const void* data, size_t size);
Status checkWire(const rgbdslam::keyframe_t*, const void* data, size_t size);
Status checkWire(const rgbdslam::map_t*, const void* data, size_t size);
Status checkWire(const rgbdslam::status_t*, const void* data, size_t size);
Status checkWire(const rgbdslam::pose_t*, const void* data, size_t size);
Status checkWire(const rgbdslam::map_receipt_t*, const void* data, size_t size);

// checkWire<T>(data, size): the check for message type T.
template <typename T>
Status checkWire(const void* data, size_t size) {
  return checkWire(static_cast<const T*>(nullptr), data, size);
}

}  // namespace rgbdslam
