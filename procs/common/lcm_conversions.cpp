#include "common/lcm_conversions.h"

#include <cmath>
#include <algorithm>
#include <cstring>

#include "rgbdslam/image/codec.h"

namespace rgbdslam {
namespace {

constexpr int kMaxImageSide = 8192;  // [px] larger claimed sizes are rejected as corrupt

void putPose(const SE3& T_w_c, double position[3], double orientation[4]) {
  const Vec3& t = T_w_c.translation();
  const Eigen::Quaterniond& q = T_w_c.rotation();
  for (int i = 0; i < 3; ++i) position[i] = t[i];
  orientation[0] = q.w(), orientation[1] = q.x(), orientation[2] = q.y(), orientation[3] = q.z();
}

Expected<SE3> getPose(const double position[3], const double orientation[4]) {
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(position[i])) return Error{"position is not finite"};
  }
  const Eigen::Quaterniond q(orientation[0], orientation[1], orientation[2], orientation[3]);
  if (!std::isfinite(q.norm()) || std::abs(q.norm() - 1.0) > 1e-3) {
    return Error{"orientation is not a unit quaternion"};
  }
  return SE3(q, Vec3(position[0], position[1], position[2]));
}

bool validSize(int width, int height) {
  return width > 0 && height > 0 && width <= kMaxImageSide && height <= kMaxImageSide;
}

std::string sizeText(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

// Raw or zlib depth bytes -> CV_16UC1; formats as in rgbd_frame_t / keyframe_t.
Expected<cv::Mat> decodeDepth(int8_t format, const std::vector<uint8_t>& bytes, int width,
                              int height) {
  if (format == rgbdslam::rgbd_frame_t::DEPTH_NONE) return cv::Mat();
  if (format == rgbdslam::rgbd_frame_t::DEPTH_ZLIB_U16) {
    auto depth = decompressDepth(bytes.data(), bytes.size(), width, height);
    if (!depth) return Error{"depth: " + depth.error()};
    return depth;
  }
  if (format == rgbdslam::keyframe_t::DEPTH_ZLIB_U16_HALF || format == rgbdslam::keyframe_t::DEPTH_ZLIB_U16_QUARTER) {
    const int step = format == rgbdslam::keyframe_t::DEPTH_ZLIB_U16_HALF ? 2 : 4;
    auto sparse = decompressDepth(bytes.data(), bytes.size(), (width + step - 1) / step, (height + step - 1) / step);
    if (!sparse) return Error{"subsampled depth: " + sparse.error()};
    cv::Mat depth(height, width, CV_16UC1);
    for (int v = 0; v < height; ++v) {
      const uint16_t* in = sparse->ptr<uint16_t>(v / step);
      uint16_t* out = depth.ptr<uint16_t>(v);
      for (int u = 0; u < width; ++u) out[u] = in[u / step];
    }
    return depth;
  }
  if (format != rgbdslam::rgbd_frame_t::DEPTH_RAW_U16) {
    return Error{"unknown depth format " + std::to_string(format)};
  }
  const size_t expected = static_cast<size_t>(width) * height * 2;
  if (bytes.size() != expected) {
    return Error{"raw depth has " + std::to_string(bytes.size()) + " bytes, " +
                 sizeText(width, height) + " needs " + std::to_string(expected)};
  }
  cv::Mat depth(height, width, CV_16UC1);
  std::memcpy(depth.data, bytes.data(), expected);
  return depth;
}

void encodeDepth(const cv::Mat& depth, bool zlib, int level, int8_t* format,
                 std::vector<uint8_t>* bytes) {
  if (depth.empty()) {
    *format = rgbdslam::rgbd_frame_t::DEPTH_NONE;
    bytes->clear();
  } else if (zlib) {
    *format = rgbdslam::rgbd_frame_t::DEPTH_ZLIB_U16;
    *bytes = compressDepth(depth, level);
  } else {
    *format = rgbdslam::rgbd_frame_t::DEPTH_RAW_U16;
    const cv::Mat contiguous = depth.isContinuous() ? depth : depth.clone();
    bytes->assign(contiguous.data, contiguous.data + contiguous.total() * 2);
  }
}

Expected<MapPointData> fromLcm(const rgbdslam::map_point_t& msg) {
  MapPointData point;
  point.id = msg.point_id;
  point.p_w = Vec3(msg.position[0], msg.position[1], msg.position[2]);
  if (!point.p_w.allFinite()) return Error{"point " + std::to_string(msg.point_id) + " position is not finite"};
  point.source_keyframe = msg.source_keyframe;
  point.uv = Eigen::Vector2d(msg.u, msg.v);
  point.level = msg.level;
  if (!point.uv.allFinite() || msg.level < 0) return Error{"point " + std::to_string(msg.point_id) + " has a bad pixel or level"};
  return point;
}

rgbdslam::map_point_t toLcm(const MapPointData& point) {
  rgbdslam::map_point_t msg;
  msg.point_id = point.id;
  for (int i = 0; i < 3; ++i) msg.position[i] = static_cast<float>(point.p_w[i]);
  msg.source_keyframe = point.source_keyframe;
  msg.u = static_cast<float>(point.uv.x());
  msg.v = static_cast<float>(point.uv.y());
  msg.level = static_cast<int8_t>(point.level);
  return msg;
}

}  // namespace

rgbdslam::rgbd_frame_t toLcm(const RgbdFrame& frame, const FrameEncoding& encoding) {
  rgbdslam::rgbd_frame_t msg;
  msg.utime = frame.utime;
  msg.seq = frame.seq;
  msg.width = frame.width();
  msg.height = frame.height();
  if (frame.colour.empty()) {
    msg.colour_format = rgbdslam::rgbd_frame_t::COLOUR_NONE;
  } else if (encoding.jpeg_colour) {
    msg.colour_format = rgbdslam::rgbd_frame_t::COLOUR_JPEG;
    msg.colour = encodeJpeg(frame.colour, encoding.jpeg_quality);
  } else {
    msg.colour_format = rgbdslam::rgbd_frame_t::COLOUR_RAW_BGR8;
    const cv::Mat contiguous = frame.colour.isContinuous() ? frame.colour : frame.colour.clone();
    msg.colour.assign(contiguous.data, contiguous.data + contiguous.total() * 3);
  }
  msg.colour_size = static_cast<int32_t>(msg.colour.size());
  encodeDepth(frame.depth, encoding.zlib_depth, encoding.zlib_level, &msg.depth_format,
              &msg.depth);
  msg.depth_size = static_cast<int32_t>(msg.depth.size());
  msg.depth_scale = static_cast<float>(frame.depth_scale);
  msg.camera_name = frame.camera_name;
  return msg;
}

Expected<RgbdFrame> fromLcm(const rgbdslam::rgbd_frame_t& msg) {
  if (!validSize(msg.width, msg.height)) return Error{"bad frame size " + sizeText(msg.width, msg.height)};
  RgbdFrame frame;
  frame.utime = msg.utime;
  frame.seq = msg.seq;
  frame.camera_name = msg.camera_name;
  frame.depth_scale = msg.depth_scale;
  if (msg.colour_format == rgbdslam::rgbd_frame_t::COLOUR_RAW_BGR8) {
    const size_t expected = static_cast<size_t>(msg.width) * msg.height * 3;
    if (msg.colour.size() != expected) {
      return Error{"raw colour has " + std::to_string(msg.colour.size()) + " bytes, " +
                   sizeText(msg.width, msg.height) + " needs " + std::to_string(expected)};
    }
    frame.colour = cv::Mat(msg.height, msg.width, CV_8UC3);
    std::memcpy(frame.colour.data, msg.colour.data(), expected);
  } else if (msg.colour_format == rgbdslam::rgbd_frame_t::COLOUR_JPEG) {
    auto colour = decodeImage(msg.colour.data(), msg.colour.size(), 3, msg.width, msg.height);
    if (!colour) return Error{"colour: " + colour.error()};
    frame.colour = *colour;
  } else if (msg.colour_format != rgbdslam::rgbd_frame_t::COLOUR_NONE) {
    return Error{"unknown colour format " + std::to_string(msg.colour_format)};
  }
  auto depth = decodeDepth(msg.depth_format, msg.depth, msg.width, msg.height);
  if (!depth) return Error{depth.error()};
  frame.depth = *depth;
  if (!frame.depth.empty() && !(std::isfinite(msg.depth_scale) && msg.depth_scale > 0)) {
    return Error{"depth_scale must be positive, got " + std::to_string(msg.depth_scale)};
  }
  if (frame.colour.empty() && frame.depth.empty()) return Error{"frame has neither colour nor depth"};
  return frame;
}

rgbdslam::pose_t toLcm(const PoseEstimate& pose) {
  rgbdslam::pose_t msg;
  msg.utime = pose.utime;
  msg.seq = pose.seq;
  putPose(pose.T_w_c, msg.position, msg.orientation);
  msg.state = static_cast<int8_t>(pose.state);
  msg.points_tracked = pose.points_tracked;
  msg.quality = static_cast<float>(pose.quality);
  msg.latency_ms = static_cast<float>(pose.latency_ms);
  return msg;
}

Expected<PoseEstimate> fromLcm(const rgbdslam::pose_t& msg) {
  auto T_w_c = getPose(msg.position, msg.orientation);
  if (!T_w_c) return Error{"pose: " + T_w_c.error()};
  if (msg.state < rgbdslam::pose_t::STATE_INITIALISING || msg.state > rgbdslam::pose_t::STATE_RELOCALISED) {
    return Error{"pose: unknown tracking state " + std::to_string(msg.state)};
  }
  PoseEstimate pose;
  pose.utime = msg.utime;
  pose.seq = msg.seq;
  pose.T_w_c = *T_w_c;
  pose.state = static_cast<TrackingState>(msg.state);
  pose.points_tracked = msg.points_tracked;
  pose.quality = msg.quality;
  pose.latency_ms = msg.latency_ms;
  return pose;
}

namespace {

// The centre pixel of each step x step block (no averaging: a mean across a depth edge would
// invent a surface that is not there); expanded again by repetition, every pixel then reads
// a measured depth at most step / 2 pixels away.
cv::Mat subsampleDepth(const cv::Mat& depth, int step) {
  cv::Mat sparse((depth.rows + step - 1) / step, (depth.cols + step - 1) / step, CV_16UC1);
  for (int v = 0; v < sparse.rows; ++v) {
    const uint16_t* in = depth.ptr<uint16_t>(std::min(step * v + step / 2, depth.rows - 1));
    uint16_t* out = sparse.ptr<uint16_t>(v);
    for (int u = 0; u < sparse.cols; ++u) out[u] = in[std::min(step * u + step / 2, depth.cols - 1)];
  }
  return sparse;
}

}  // namespace

rgbdslam::keyframe_t toLcm(const KeyframeData& keyframe, const KeyframeEncoding& encoding) {
  rgbdslam::keyframe_t msg;
  msg.utime = keyframe.utime;
  msg.map_id = keyframe.map_id;
  msg.keyframe_id = keyframe.id;
  putPose(keyframe.T_w_c, msg.position, msg.orientation);
  msg.width = keyframe.grey.cols;
  msg.height = keyframe.grey.rows;
  msg.grey_format = encoding.jpeg_grey ? rgbdslam::keyframe_t::GREY_JPEG : rgbdslam::keyframe_t::GREY_PNG;
  msg.grey = encoding.jpeg_grey ? encodeJpeg(keyframe.grey, encoding.jpeg_quality) : encodePng(keyframe.grey);
  msg.grey_size = static_cast<int32_t>(msg.grey.size());
  if (encoding.depth_step > 1 && !keyframe.depth.empty()) {
    const int step = encoding.depth_step >= 4 ? 4 : 2;
    msg.depth_format = step == 2 ? rgbdslam::keyframe_t::DEPTH_ZLIB_U16_HALF : rgbdslam::keyframe_t::DEPTH_ZLIB_U16_QUARTER;
    msg.depth = compressDepth(subsampleDepth(keyframe.depth, step), 6);
  } else {
    encodeDepth(keyframe.depth, true, 1, &msg.depth_format, &msg.depth);
  }
  msg.depth_size = static_cast<int32_t>(msg.depth.size());
  msg.depth_scale = static_cast<float>(keyframe.depth_scale);
  for (const auto& m : keyframe.measurements) {
    rgbdslam::measurement_t out;
    out.point_id = m.point_id;
    out.u = static_cast<float>(m.uv.x());
    out.v = static_cast<float>(m.uv.y());
    out.level = static_cast<int8_t>(m.level);
    out.depth = static_cast<float>(m.depth);
    msg.measurements.push_back(out);
  }
  msg.num_measurements = static_cast<int32_t>(msg.measurements.size());
  for (const auto& p : keyframe.new_points) msg.new_points.push_back(toLcm(p));
  msg.num_new_points = static_cast<int32_t>(msg.new_points.size());
  return msg;
}

Expected<KeyframeData> fromLcm(const rgbdslam::keyframe_t& msg) {
  const std::string what = "keyframe " + std::to_string(msg.keyframe_id) + ": ";
  if (msg.keyframe_id < 0) return Error{what + "negative id"};
  if (!validSize(msg.width, msg.height)) return Error{what + "bad size " + sizeText(msg.width, msg.height)};
  auto T_w_c = getPose(msg.position, msg.orientation);
  if (!T_w_c) return Error{what + T_w_c.error()};
  KeyframeData keyframe;
  keyframe.utime = msg.utime;
  keyframe.map_id = msg.map_id;
  keyframe.id = msg.keyframe_id;
  keyframe.T_w_c = *T_w_c;
  if (msg.grey_format == rgbdslam::keyframe_t::GREY_RAW_U8) {
    if (msg.grey.size() != static_cast<size_t>(msg.width) * msg.height) return Error{what + "raw grey image has the wrong size"};
    keyframe.grey = cv::Mat(msg.height, msg.width, CV_8UC1);
    std::memcpy(keyframe.grey.data, msg.grey.data(), msg.grey.size());
  } else if (msg.grey_format == rgbdslam::keyframe_t::GREY_JPEG || msg.grey_format == rgbdslam::keyframe_t::GREY_PNG) {
    auto grey = decodeImage(msg.grey.data(), msg.grey.size(), 1, msg.width, msg.height);
    if (!grey) return Error{what + "grey: " + grey.error()};
    keyframe.grey = *grey;
  } else {
    return Error{what + "unknown grey format " + std::to_string(msg.grey_format)};
  }
  auto depth = decodeDepth(msg.depth_format, msg.depth, msg.width, msg.height);
  if (!depth) return Error{what + depth.error()};
  keyframe.depth = *depth;
  keyframe.depth_scale = msg.depth_scale;
  for (const auto& m : msg.measurements) {
    if (!std::isfinite(m.u) || !std::isfinite(m.v) || m.level < 0 || !std::isfinite(m.depth) || m.depth < 0) {
      return Error{what + "measurement of point " + std::to_string(m.point_id) + " is malformed"};
    }
    keyframe.measurements.push_back({m.point_id, Eigen::Vector2d(m.u, m.v), m.level, m.depth});
  }
  for (const auto& p : msg.new_points) {
    auto point = fromLcm(p);
    if (!point) return Error{what + point.error()};
    keyframe.new_points.push_back(*point);
  }
  return keyframe;
}

rgbdslam::map_t toLcm(const MapUpdate& update) {
  rgbdslam::map_t msg;
  msg.utime = update.utime;
  msg.map_id = update.map_id;
  msg.version = update.version;
  msg.is_snapshot = update.is_snapshot;
  msg.acked_keyframes = update.acked_keyframes;
  msg.num_acked = static_cast<int32_t>(msg.acked_keyframes.size());
  for (const auto& kf : update.keyframes) {
    rgbdslam::keyframe_pose_t out;
    out.keyframe_id = kf.id;
    putPose(kf.T_w_c, out.position, out.orientation);
    msg.keyframes.push_back(out);
  }
  msg.num_keyframes = static_cast<int32_t>(msg.keyframes.size());
  for (const auto& p : update.points) msg.points.push_back(toLcm(p));
  msg.num_points = static_cast<int32_t>(msg.points.size());
  for (const auto& moved : update.moved_points) {
    rgbdslam::point_position_t out;
    out.point_id = moved.id;
    for (int i = 0; i < 3; ++i) out.position[i] = static_cast<float>(moved.p_w[i]);
    msg.moved.push_back(out);
  }
  msg.num_moved = static_cast<int32_t>(msg.moved.size());
  msg.removed_points = update.removed_points;
  msg.num_removed = static_cast<int32_t>(msg.removed_points.size());
  return msg;
}

Expected<MapUpdate> fromLcm(const rgbdslam::map_t& msg) {
  const std::string what = "map version " + std::to_string(msg.version) + ": ";
  if (msg.version < 0) return Error{what + "negative version"};
  MapUpdate update;
  update.utime = msg.utime;
  update.map_id = msg.map_id;
  update.version = msg.version;
  update.is_snapshot = msg.is_snapshot;
  update.acked_keyframes = msg.acked_keyframes;
  for (const auto& kf : msg.keyframes) {
    auto T_w_c = getPose(kf.position, kf.orientation);
    if (!T_w_c) return Error{what + "keyframe " + std::to_string(kf.keyframe_id) + " " + T_w_c.error()};
    update.keyframes.push_back({kf.keyframe_id, *T_w_c});
  }
  for (const auto& p : msg.points) {
    auto point = fromLcm(p);
    if (!point) return Error{what + point.error()};
    update.points.push_back(*point);
  }
  for (const auto& moved : msg.moved) {
    const Vec3 p_w(moved.position[0], moved.position[1], moved.position[2]);
    if (!p_w.allFinite()) return Error{what + "moved point " + std::to_string(moved.point_id) + " position is not finite"};
    update.moved_points.push_back({moved.point_id, p_w});
  }
  update.removed_points = msg.removed_points;
  return update;
}

rgbdslam::map_receipt_t toLcm(const MapReceipt& receipt) {
  rgbdslam::map_receipt_t msg;
  msg.utime = receipt.utime;
  msg.map_id = receipt.map_id;
  msg.applied_version = receipt.applied_version;
  msg.newest_version_seen = receipt.newest_version_seen;
  msg.keyframes_created = receipt.keyframes_created;
  msg.keyframes_unacked = receipt.keyframes_unacked;
  return msg;
}

Expected<MapReceipt> fromLcm(const rgbdslam::map_receipt_t& msg) {
  if (msg.map_id <= 0) return Error{"map receipt for map id " + std::to_string(msg.map_id) + " (must be > 0)"};
  if (msg.applied_version < 0 || msg.newest_version_seen < msg.applied_version) {
    return Error{"map receipt with applied version " + std::to_string(msg.applied_version) +
                 " and newest seen " + std::to_string(msg.newest_version_seen) +
                 " (need 0 <= applied <= newest seen)"};
  }
  if (msg.keyframes_created < 0 || msg.keyframes_unacked < 0 || msg.keyframes_unacked > msg.keyframes_created) {
    return Error{"map receipt with " + std::to_string(msg.keyframes_unacked) + " of " +
                 std::to_string(msg.keyframes_created) + " keyframes unacknowledged"};
  }
  MapReceipt r;
  r.utime = msg.utime;
  r.map_id = msg.map_id;
  r.applied_version = msg.applied_version;
  r.newest_version_seen = msg.newest_version_seen;
  r.keyframes_created = msg.keyframes_created;
  r.keyframes_unacked = msg.keyframes_unacked;
  return r;
}

rgbdslam::status_t toLcm(const ComponentStatus& status) {
  rgbdslam::status_t msg;
  msg.utime = status.utime;
  msg.component = status.component;
  msg.state = status.state;
  for (const auto& [name, value] : status.counters) {
    msg.counter_names.push_back(name);
    msg.counter_values.push_back(value);
  }
  msg.num_counters = static_cast<int32_t>(msg.counter_names.size());
  for (const auto& [name, value] : status.timings_ms) {
    msg.timing_names.push_back(name);
    msg.timing_values_ms.push_back(static_cast<float>(value));
  }
  msg.num_timings = static_cast<int32_t>(msg.timing_names.size());
  return msg;
}

Expected<ComponentStatus> fromLcm(const rgbdslam::status_t& msg) {
  ComponentStatus status;
  status.utime = msg.utime;
  status.component = msg.component;
  status.state = msg.state;
  for (int i = 0; i < msg.num_counters; ++i) status.counters.emplace_back(msg.counter_names[i], msg.counter_values[i]);
  for (int i = 0; i < msg.num_timings; ++i) status.timings_ms.emplace_back(msg.timing_names[i], msg.timing_values_ms[i]);
  return status;
}

}  // namespace rgbdslam
