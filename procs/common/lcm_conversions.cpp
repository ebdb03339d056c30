#include "common/lcm_conversions.h"

#include <cmath>
#include <algorithm>
#include <cstdio>
#include <cstring>

#include "common/protocol_limits.h"
#include "rgbdslam/image/codec.h"
#include "rgbdslam/image/corners.h"
#include "rgbdslam/image/pyramid.h"

namespace rgbdslam {
namespace {

using limits::kMaxImageSide;

void putPose(const SE3& T_w_c, double position[3], double orientation[4]) {
  const Vec3& t = T_w_c.translation();
  const Eigen::Quaterniond& q = T_w_c.rotation();
  for (int i = 0; i < 3; ++i) position[i] = t[i];
  orientation[0] = q.w(), orientation[1] = q.x(), orientation[2] = q.y(), orientation[3] = q.z();
}

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

// A position in the world: finite and within the protocol's world bound on every axis.
Status checkWorld(const Vec3& p_w, const std::string& what) {
  if (!p_w.allFinite()) return Error{what + " is not finite"};
  if (p_w.cwiseAbs().maxCoeff() > limits::kMaxWorldCoordinateM) {
    return Error{what + " (" + number(p_w.x()) + ", " + number(p_w.y()) + ", " + number(p_w.z()) +
                 ") m is beyond the world bound of " + number(limits::kMaxWorldCoordinateM) + " m"};
  }
  return Status{};
}

Expected<SE3> getPose(const double position[3], const double orientation[4]) {
  if (Status s = checkWorld(Vec3(position[0], position[1], position[2]), "position"); !s) return Error{s.error()};
  const Eigen::Quaterniond q(orientation[0], orientation[1], orientation[2], orientation[3]);
  if (!std::isfinite(q.norm()) || std::abs(q.norm() - 1.0) > limits::kQuaternionNormTolerance) {
    return Error{"orientation is not a unit quaternion"};
  }
  return SE3(q, Vec3(position[0], position[1], position[2]));
}

// A pyramid level the keyframe's pyramid has.
Status checkLevel(int level, const std::string& what) {
  if (level < 0 || level >= limits::kMaxLevels) {
    return Error{what + " has pyramid level " + std::to_string(level) + ", outside [0, " +
                 std::to_string(limits::kMaxLevels - 1) + "]"};
  }
  return Status{};
}

// A level-0 pixel inside a width x height image (pixel centres at whole numbers, so the
// image covers [-0.5, width - 0.5) x [-0.5, height - 0.5)).
Status checkPixel(double u, double v, int width, int height, const std::string& what) {
  if (!(u >= -0.5 && u < width - 0.5 && v >= -0.5 && v < height - 0.5)) {
    return Error{what + " pixel (" + number(u) + ", " + number(v) + ") is outside the " +
                 std::to_string(width) + "x" + std::to_string(height) + " image"};
  }
  return Status{};
}

Status checkId(int64_t id, const std::string& what) {
  if (id < 0) return Error{what + " has a negative id " + std::to_string(id)};
  return Status{};
}

// A message built in memory (not decoded) may carry a count that disagrees with its array.
Status checkCount(int64_t count, size_t actual, const char* field) {
  if (count < 0 || static_cast<size_t>(count) != actual) {
    return Error{std::string(field) + " is " + std::to_string(count) + " but the array holds " + std::to_string(actual)};
  }
  return Status{};
}

Status checkDepthScale(double scale) {
  if (!(std::isfinite(scale) && scale > 0 && scale <= limits::kMaxDepthScale)) {
    return Error{"depth_scale must be in (0, " + number(limits::kMaxDepthScale) + "], got " + number(scale)};
  }
  return Status{};
}

bool validSize(int width, int height) {
  return width > 0 && height > 0 && width <= kMaxImageSide && height <= kMaxImageSide;
}

std::string sizeText(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

// The pixel and row step of a subsampled keyframe depth format; 1 for the others.
int subsampledDepthStep(int8_t format) {
  using K = rgbdslam::keyframe_t;
  switch (format) {
    case K::DEPTH_ZLIB_U16_HALF: case K::DEPTH_INVERSE_ZSTD_HALF: return 2;
    case K::DEPTH_ZLIB_U16_QUARTER: case K::DEPTH_INVERSE_ZSTD_QUARTER: return 4;
    case K::DEPTH_ZLIB_U16_EIGHTH: case K::DEPTH_INVERSE_ZSTD_EIGHTH: return 8;
    default: return 1;
  }
}

// 'image' as rows x cols of 'type', keeping its buffer when it has that size and nothing
// else holds it (cv::Mat::create alone would keep a buffer another Mat still reads).
void reuseOrCreate(cv::Mat* image, int rows, int cols, int type) {
  if (!image->u || image->u->refcount != 1 || !image->isContinuous()) image->release();
  image->create(rows, cols, type);
}

// Raw pixels of 'type' into 'image' (reused), or an error naming 'what'.
Status copyRaw(const std::vector<uint8_t>& bytes, int width, int height, int type, const std::string& what,
               cv::Mat* image) {
  const size_t expected = static_cast<size_t>(width) * height * CV_ELEM_SIZE(type);
  if (bytes.size() != expected) {
    return Error{what + " has " + std::to_string(bytes.size()) + " bytes, " + sizeText(width, height) + " needs " +
                 std::to_string(expected)};
  }
  reuseOrCreate(image, height, width, type);
  std::memcpy(image->data, bytes.data(), expected);
  return Status{};
}

// Raw, zlib or inverse-depth bytes -> CV_16UC1 at depth_scale units per metre; formats as
// in rgbd_frame_t / keyframe_t.
Expected<cv::Mat> decodeDepth(int8_t format, const std::vector<uint8_t>& bytes, int width,
                              int height, double depth_scale) {
  if (format == rgbdslam::rgbd_frame_t::DEPTH_NONE) return cv::Mat();
  if (format == rgbdslam::rgbd_frame_t::DEPTH_ZLIB_U16) {
    auto depth = decompressDepth(bytes.data(), bytes.size(), width, height);
    if (!depth) return Error{"depth: " + depth.error()};
    return depth;
  }
  using K = rgbdslam::keyframe_t;
  if (format == K::DEPTH_INVERSE_ZSTD) {
    auto depth = decompressInverseDepth(bytes.data(), bytes.size(), width, height, depth_scale);
    if (!depth) return Error{"depth: " + depth.error()};
    return depth;
  }
  const int step = subsampledDepthStep(format);
  if (step > 1) {
    const int sparse_width = (width + step - 1) / step, sparse_height = (height + step - 1) / step;
    const bool inverse = format == K::DEPTH_INVERSE_ZSTD_HALF || format == K::DEPTH_INVERSE_ZSTD_QUARTER ||
                         format == K::DEPTH_INVERSE_ZSTD_EIGHTH;
    auto sparse = inverse ? decompressInverseDepth(bytes.data(), bytes.size(), sparse_width, sparse_height, depth_scale)
                          : decompressDepth(bytes.data(), bytes.size(), sparse_width, sparse_height);
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
  cv::Mat depth;
  if (Status copied = copyRaw(bytes, width, height, CV_16UC1, "raw depth", &depth); !copied) return Error{copied.error()};
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

// A map point; its pixel lies in a width x height source keyframe (the largest image when
// the source keyframe's size is not at hand, as in map_t).
Expected<MapPointData> fromLcm(const rgbdslam::map_point_t& msg, int width = kMaxImageSide,
                               int height = kMaxImageSide) {
  const std::string what = "point " + std::to_string(msg.point_id);
  MapPointData point;
  point.id = msg.point_id;
  point.p_w = Vec3(msg.position[0], msg.position[1], msg.position[2]);
  point.source_keyframe = msg.source_keyframe;
  point.uv = Eigen::Vector2d(msg.u, msg.v);
  point.level = msg.level;
  for (Status s : {checkId(msg.point_id, what), checkId(msg.source_keyframe, what + " source keyframe"),
                   checkWorld(point.p_w, what + " position"), checkLevel(msg.level, what),
                   checkPixel(msg.u, msg.v, width, height, what)}) {
    if (!s) return Error{s.error()};
  }
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
  RgbdFrame frame;
  if (Status converted = fromLcm(msg, &frame); !converted) return Error{converted.error()};
  return frame;
}

Status fromLcm(const rgbdslam::rgbd_frame_t& msg, RgbdFrame* frame) {
  if (!validSize(msg.width, msg.height)) return Error{"bad frame size " + sizeText(msg.width, msg.height)};
  for (Status s : {checkCount(msg.colour_size, msg.colour.size(), "colour_size"),
                   checkCount(msg.depth_size, msg.depth.size(), "depth_size"),
                   checkId(msg.seq, "frame sequence number")}) {
    if (!s) return Error{"frame " + std::to_string(msg.seq) + ": " + s.error()};
  }
  frame->utime = msg.utime;
  frame->seq = msg.seq;
  frame->camera_name = msg.camera_name;
  frame->depth_scale = msg.depth_scale;
  if (msg.colour_format == rgbdslam::rgbd_frame_t::COLOUR_RAW_BGR8) {
    if (Status s = copyRaw(msg.colour, msg.width, msg.height, CV_8UC3, "raw colour", &frame->colour); !s) return s;
  } else if (msg.colour_format == rgbdslam::rgbd_frame_t::COLOUR_JPEG) {
    auto colour = decodeImage(msg.colour.data(), msg.colour.size(), 3, msg.width, msg.height);
    if (!colour) return Error{"colour: " + colour.error()};
    frame->colour = *colour;
  } else if (msg.colour_format == rgbdslam::rgbd_frame_t::COLOUR_NONE) {
    frame->colour.release();
  } else {
    return Error{"unknown colour format " + std::to_string(msg.colour_format)};
  }
  // A frame carries its depth whole (raw or zlib); the keyframe formats are not for frames.
  if (msg.depth_format == rgbdslam::rgbd_frame_t::DEPTH_RAW_U16) {
    if (Status s = copyRaw(msg.depth, msg.width, msg.height, CV_16UC1, "raw depth", &frame->depth); !s) return s;
  } else if (msg.depth_format == rgbdslam::rgbd_frame_t::DEPTH_ZLIB_U16 ||
             msg.depth_format == rgbdslam::rgbd_frame_t::DEPTH_NONE) {
    auto depth = decodeDepth(msg.depth_format, msg.depth, msg.width, msg.height, msg.depth_scale);
    if (!depth) return Error{depth.error()};
    frame->depth = *depth;
  } else {
    return Error{"depth format " + std::to_string(msg.depth_format) + " is not a frame's (raw, zlib or none)"};
  }
  if (!frame->depth.empty()) {
    if (Status s = checkDepthScale(msg.depth_scale); !s) return Error{s.error()};
  }
  if (frame->colour.empty() && frame->depth.empty()) return Error{"frame has neither colour nor depth"};
  return Status{};
}

Status decodeFrame(const void* data, size_t size, rgbdslam::rgbd_frame_t* msg, RgbdFrame* frame) {
  msg->colour.clear();  // liblcm leaves an array whose count is 0 as it was
  msg->depth.clear();
  if (Status decoded = decodeMessage(data, size, msg); !decoded) return decoded;
  return fromLcm(*msg, frame);
}

rgbdslam::pose_t toLcm(const PoseEstimate& pose, int64_t map_id) {
  rgbdslam::pose_t msg;
  msg.utime = pose.utime;
  msg.seq = pose.seq;
  msg.map_id = map_id;
  putPose(pose.T_w_c, msg.position, msg.orientation);
  putPose(pose.map_T_w_c, msg.map_position, msg.map_orientation);
  msg.part = pose.part;
  msg.state = static_cast<int8_t>(pose.state);
  msg.points_tracked = pose.points_tracked;
  msg.quality = static_cast<float>(pose.quality);
  msg.latency_ms = static_cast<float>(pose.latency_ms);
  return msg;
}

Expected<MapPose> fromLcm(const rgbdslam::pose_t& msg) {
  const std::string what = "pose " + std::to_string(msg.seq) + ": ";
  auto T_w_c = getPose(msg.position, msg.orientation);
  if (!T_w_c) return Error{what + T_w_c.error()};
  auto map_T_w_c = getPose(msg.map_position, msg.map_orientation);
  if (!map_T_w_c) return Error{what + "map pose: " + map_T_w_c.error()};
  if (msg.state < rgbdslam::pose_t::STATE_INITIALISING || msg.state > rgbdslam::pose_t::STATE_RELOCALISED) {
    return Error{what + "unknown tracking state " + std::to_string(msg.state)};
  }
  for (Status s : {checkId(msg.seq, "sequence number"), checkId(msg.map_id, "map"), checkId(msg.part, "part")}) {
    if (!s) return Error{what + s.error()};
  }
  if (msg.points_tracked < 0) return Error{what + "points_tracked is negative"};
  if (!(msg.quality >= 0 && msg.quality <= 1)) return Error{what + "quality " + number(msg.quality) + " is outside [0, 1]"};
  if (!std::isfinite(msg.latency_ms)) return Error{what + "latency is not finite"};
  MapPose out;
  out.map_id = msg.map_id;
  PoseEstimate& pose = out.pose;
  pose.utime = msg.utime;
  pose.seq = msg.seq;
  pose.T_w_c = *T_w_c;
  pose.map_T_w_c = *map_T_w_c;
  pose.part = msg.part;
  pose.state = static_cast<TrackingState>(msg.state);
  pose.points_tracked = msg.points_tracked;
  pose.quality = msg.quality;
  pose.latency_ms = msg.latency_ms;
  return out;
}

namespace {

// The centre pixel of each step x step block (no averaging: a mean across a depth edge would
// invent a surface that is not there); expanded again by repetition. The map reads a pixel
// between four readings of one smooth surface as their interpolation, else as its block's
// reading (map/keyframe_depth.h), so the sample must stay at the block's centre.
cv::Mat subsampleDepth(const cv::Mat& depth, int step) {
  cv::Mat sparse((depth.rows + step - 1) / step, (depth.cols + step - 1) / step, CV_16UC1);
  for (int v = 0; v < sparse.rows; ++v) {
    const uint16_t* in = depth.ptr<uint16_t>(std::min(step * v + step / 2, depth.rows - 1));
    uint16_t* out = sparse.ptr<uint16_t>(v);
    for (int u = 0; u < sparse.cols; ++u) out[u] = in[std::min(step * u + step / 2, depth.cols - 1)];
  }
  return sparse;
}

// 'depth' (at every step-th pixel and row of 'grey') with no reading (0) away from the
// grey image's FAST corners (KeyframeEncoding::depth_near_corners). The mapper detects its
// corners in the decoded JPEG, kLossyCornerMargin (4) below the thresholds (corners.h), and
// the JPEG's error moves scores further, so the corners here are taken kDepthCornerMargin
// below. Measured on a corridor frame at quality 45 (test_lcm_conversions), the share of
// the depth readings at the mapper's corners that stay, and the depth's bytes: margin 4,
// 94.6 % (3.8 of 6.6 kB); 6, 99.3 % (4.1 kB); 8, more bytes than the whole depth (9.3 kB:
// FAST at 2 grey levels finds the noise, and the holes between break the prediction).
constexpr int kDepthCornerMargin = 6;  // [grey levels]

cv::Mat depthNearCorners(const cv::Mat& depth, const cv::Mat& grey, int step) {
  std::vector<LevelCorners> corners;
  detectPyramidCorners(buildPyramid(grey), lossyCornerOptions(CornerOptions{}, kDepthCornerMargin),
                       /*with_maxima=*/false, &corners);
  const cv::Mat mask = cornerBlockMask(corners, step, grey.size());
  cv::Mat out = depth.clone();
  if (mask.size() == out.size()) out.setTo(0, mask == 0);
  return out;
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
  msg.grey = encoding.jpeg_grey ? encodeJpeg(keyframe.grey, encoding.jpeg_quality, /*optimal_huffman=*/true) : encodePng(keyframe.grey);
  msg.grey_size = static_cast<int32_t>(msg.grey.size());
  using K = rgbdslam::keyframe_t;
  const bool inverse = encoding.inverse_depth_step > 0 && keyframe.depth_scale > 0;
  const int step = encoding.depth_step >= 8 ? 8 : encoding.depth_step >= 4 ? 4 : encoding.depth_step >= 2 ? 2 : 1;
  const cv::Mat depth = step == 1 || keyframe.depth.empty() ? keyframe.depth : subsampleDepth(keyframe.depth, step);
  const auto compress = [&](const cv::Mat& d) {
    return inverse ? compressInverseDepth(d, keyframe.depth_scale, encoding.inverse_depth_step)
                   : compressDepth(d, step == 1 ? 1 : 6);
  };
  if (!depth.empty()) {
    msg.depth_format = inverse ? (step == 1 ? K::DEPTH_INVERSE_ZSTD : step == 2 ? K::DEPTH_INVERSE_ZSTD_HALF
                                  : step == 4 ? K::DEPTH_INVERSE_ZSTD_QUARTER : K::DEPTH_INVERSE_ZSTD_EIGHTH)
                               : (step == 1 ? K::DEPTH_ZLIB_U16 : step == 2 ? K::DEPTH_ZLIB_U16_HALF
                                  : step == 4 ? K::DEPTH_ZLIB_U16_QUARTER : K::DEPTH_ZLIB_U16_EIGHTH);
    msg.depth = compress(depth);
    // Where corners are everywhere (a richly textured view) the mask keeps nearly all of
    // the depth, and its holes cost the predictor more than they save: the whole goes then.
    if (encoding.depth_near_corners && !keyframe.grey.empty()) {
      std::vector<uint8_t> near = compress(depthNearCorners(depth, keyframe.grey, step));
      if (near.size() < msg.depth.size()) msg.depth = std::move(near);
    }
  } else {
    encodeDepth(depth, true, 1, &msg.depth_format, &msg.depth);  // DEPTH_NONE
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
  msg.new_part = keyframe.new_part;
  msg.anchor_keyframe_id = keyframe.anchor;
  putPose(keyframe.T_w_anchor, msg.anchor_position, msg.anchor_orientation);
  return msg;
}

namespace {

// The keyframe's counts, id, size and pose; the images and points come after.
Status checkKeyframeHeader(const rgbdslam::keyframe_t& msg) {
  for (Status s : {checkId(msg.keyframe_id, "keyframe"), checkId(msg.map_id, "map"),
                   checkCount(msg.grey_size, msg.grey.size(), "grey_size"),
                   checkCount(msg.depth_size, msg.depth.size(), "depth_size"),
                   checkCount(msg.num_measurements, msg.measurements.size(), "num_measurements"),
                   checkCount(msg.num_new_points, msg.new_points.size(), "num_new_points")}) {
    if (!s) return s;
  }
  if (!validSize(msg.width, msg.height)) return Error{"bad size " + sizeText(msg.width, msg.height)};
  return Status{};
}

Status decodeGrey(const rgbdslam::keyframe_t& msg, KeyframeData* keyframe) {
  if (msg.grey_format == rgbdslam::keyframe_t::GREY_RAW_U8) {
    if (msg.grey.size() != static_cast<size_t>(msg.width) * msg.height) return Error{"raw grey image has the wrong size"};
    keyframe->grey = cv::Mat(msg.height, msg.width, CV_8UC1);
    std::memcpy(keyframe->grey.data, msg.grey.data(), msg.grey.size());
  } else if (msg.grey_format == rgbdslam::keyframe_t::GREY_JPEG || msg.grey_format == rgbdslam::keyframe_t::GREY_PNG) {
    auto grey = decodeImage(msg.grey.data(), msg.grey.size(), 1, msg.width, msg.height);
    if (!grey) return Error{"grey: " + grey.error()};
    keyframe->grey = *grey;
    keyframe->grey_lossy = msg.grey_format == rgbdslam::keyframe_t::GREY_JPEG;
  } else {
    return Error{"unknown grey format " + std::to_string(msg.grey_format)};
  }
  return Status{};
}

// A measurement of an existing point in this keyframe: id, pixel, level and depth in range.
Expected<Measurement> fromLcm(const rgbdslam::measurement_t& m, int width, int height) {
  const std::string what = "measurement of point " + std::to_string(m.point_id);
  for (Status s : {checkId(m.point_id, what), checkLevel(m.level, what),
                   checkPixel(m.u, m.v, width, height, what)}) {
    if (!s) return Error{s.error()};
  }
  if (!(m.depth >= 0 && m.depth <= limits::kMaxDepthM)) {
    return Error{what + " has depth " + number(m.depth) + " m, outside [0, " + number(limits::kMaxDepthM) + "]"};
  }
  return Measurement{m.point_id, Eigen::Vector2d(m.u, m.v), m.level, m.depth};
}

Status decodeKeyframePoints(const rgbdslam::keyframe_t& msg, KeyframeData* keyframe) {
  for (const auto& m : msg.measurements) {
    auto measurement = fromLcm(m, msg.width, msg.height);
    if (!measurement) return Error{measurement.error()};
    keyframe->measurements.push_back(*measurement);
  }
  for (const auto& p : msg.new_points) {
    auto point = fromLcm(p, msg.width, msg.height);
    if (!point) return Error{point.error()};
    if (point->source_keyframe != msg.keyframe_id) {
      return Error{"new point " + std::to_string(p.point_id) + " names keyframe " +
                   std::to_string(point->source_keyframe) + " as its source"};
    }
    keyframe->new_points.push_back(*point);
  }
  return Status{};
}

}  // namespace

Expected<KeyframeData> fromLcm(const rgbdslam::keyframe_t& msg) {
  const std::string what = "keyframe " + std::to_string(msg.keyframe_id) + ": ";
  if (Status s = checkKeyframeHeader(msg); !s) return Error{what + s.error()};
  auto T_w_c = getPose(msg.position, msg.orientation);
  if (!T_w_c) return Error{what + T_w_c.error()};
  KeyframeData keyframe;
  keyframe.utime = msg.utime;
  keyframe.map_id = msg.map_id;
  keyframe.id = msg.keyframe_id;
  keyframe.T_w_c = *T_w_c;
  keyframe.new_part = msg.new_part;
  if (msg.anchor_keyframe_id >= 0) {  // -1: none
    if (msg.anchor_keyframe_id >= msg.keyframe_id) {
      return Error{what + "anchor keyframe " + std::to_string(msg.anchor_keyframe_id) + " is not older than the keyframe"};
    }
    auto T_w_anchor = getPose(msg.anchor_position, msg.anchor_orientation);
    if (!T_w_anchor) return Error{what + "anchor: " + T_w_anchor.error()};
    keyframe.anchor = msg.anchor_keyframe_id;
    keyframe.T_w_anchor = *T_w_anchor;
  } else if (msg.anchor_keyframe_id != -1) {
    return Error{what + "anchor keyframe id " + std::to_string(msg.anchor_keyframe_id) + " (-1 or an older keyframe)"};
  }
  if (Status s = decodeGrey(msg, &keyframe); !s) return Error{what + s.error()};
  if (msg.depth_format != rgbdslam::keyframe_t::DEPTH_NONE) {  // the inverse-depth decoder reads the scale
    if (Status s = checkDepthScale(msg.depth_scale); !s) return Error{what + s.error()};
  }
  auto depth = decodeDepth(msg.depth_format, msg.depth, msg.width, msg.height, msg.depth_scale);
  if (!depth) return Error{what + depth.error()};
  keyframe.depth = *depth;
  keyframe.depth_scale = msg.depth_scale;
  if (!keyframe.depth.empty()) {
    if (Status s = checkDepthScale(msg.depth_scale); !s) return Error{what + s.error()};
  }
  if (Status s = decodeKeyframePoints(msg, &keyframe); !s) return Error{what + s.error()};
  return keyframe;
}

rgbdslam::map_t toLcm(const MapUpdate& update) {
  rgbdslam::map_t msg;
  msg.utime = update.utime;
  msg.map_id = update.map_id;
  msg.version = update.version;
  msg.is_snapshot = update.is_snapshot;
  msg.acked_below = update.acked_below;
  for (const auto& kf : update.keyframes) {
    rgbdslam::keyframe_pose_t out;
    out.keyframe_id = kf.id;
    putPose(kf.T_w_c, out.position, out.orientation);
    out.part = kf.part;
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
  msg.removed_keyframes = update.removed_keyframes;
  msg.num_removed_keyframes = static_cast<int32_t>(msg.removed_keyframes.size());
  return msg;
}

namespace {

Status checkMapHeader(const rgbdslam::map_t& msg) {
  for (Status s : {checkId(msg.map_id, "map"), checkId(msg.acked_below, "acknowledged keyframes' end"),
                   checkCount(msg.num_keyframes, msg.keyframes.size(), "num_keyframes"),
                   checkCount(msg.num_points, msg.points.size(), "num_points"),
                   checkCount(msg.num_moved, msg.moved.size(), "num_moved"),
                   checkCount(msg.num_removed, msg.removed_points.size(), "num_removed"),
                   checkCount(msg.num_removed_keyframes, msg.removed_keyframes.size(), "num_removed_keyframes")}) {
    if (!s) return s;
  }
  if (msg.version < 0) return Error{"negative version"};
  for (int64_t id : msg.removed_points) {
    if (Status s = checkId(id, "removed point"); !s) return s;
  }
  for (int64_t id : msg.removed_keyframes) {
    if (Status s = checkId(id, "removed keyframe"); !s) return s;
  }
  return Status{};
}

Status decodeMapContents(const rgbdslam::map_t& msg, MapUpdate* update) {
  for (const auto& kf : msg.keyframes) {
    const std::string what = "keyframe " + std::to_string(kf.keyframe_id);
    if (Status s = checkId(kf.keyframe_id, what); !s) return s;
    auto T_w_c = getPose(kf.position, kf.orientation);
    if (!T_w_c) return Error{what + " " + T_w_c.error()};
    // A part is named by the keyframe that started it: never a later one.
    if (kf.part < 0 || kf.part > kf.keyframe_id) {
      return Error{what + " in part " + std::to_string(kf.part) + " (need 0 <= part <= keyframe id)"};
    }
    update->keyframes.push_back({kf.keyframe_id, *T_w_c, kf.part});
  }
  for (const auto& p : msg.points) {
    auto point = fromLcm(p);
    if (!point) return Error{point.error()};
    update->points.push_back(*point);
  }
  for (const auto& moved : msg.moved) {
    const std::string what = "moved point " + std::to_string(moved.point_id);
    const Vec3 p_w(moved.position[0], moved.position[1], moved.position[2]);
    for (Status s : {checkId(moved.point_id, what), checkWorld(p_w, what + " position")}) {
      if (!s) return s;
    }
    update->moved_points.push_back({moved.point_id, p_w});
  }
  return Status{};
}

}  // namespace

Expected<MapUpdate> fromLcm(const rgbdslam::map_t& msg) {
  const std::string what = "map version " + std::to_string(msg.version) + ": ";
  if (Status s = checkMapHeader(msg); !s) return Error{what + s.error()};
  MapUpdate update;
  update.utime = msg.utime;
  update.map_id = msg.map_id;
  update.version = msg.version;
  update.is_snapshot = msg.is_snapshot;
  update.acked_below = msg.acked_below;
  if (Status s = decodeMapContents(msg, &update); !s) return Error{what + s.error()};
  update.removed_points = msg.removed_points;
  update.removed_keyframes = msg.removed_keyframes;
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
  msg.keyframes_sendable_from = receipt.keyframes_sendable_from;
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
  if (msg.keyframes_sendable_from < 0 || msg.keyframes_sendable_from > msg.keyframes_created) {
    return Error{"map receipt that can send from keyframe " + std::to_string(msg.keyframes_sendable_from) +
                 " of " + std::to_string(msg.keyframes_created) + " (need 0 <= from <= created)"};
  }
  MapReceipt r;
  r.utime = msg.utime;
  r.map_id = msg.map_id;
  r.applied_version = msg.applied_version;
  r.newest_version_seen = msg.newest_version_seen;
  r.keyframes_created = msg.keyframes_created;
  r.keyframes_unacked = msg.keyframes_unacked;
  r.keyframes_sendable_from = msg.keyframes_sendable_from;
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
  for (Status s : {checkCount(msg.num_counters, msg.counter_names.size(), "num_counters"),
                   checkCount(msg.num_counters, msg.counter_values.size(), "num_counters"),
                   checkCount(msg.num_timings, msg.timing_names.size(), "num_timings"),
                   checkCount(msg.num_timings, msg.timing_values_ms.size(), "num_timings")}) {
    if (!s) return Error{"status of " + msg.component + ": " + s.error()};
  }
  ComponentStatus status;
  status.utime = msg.utime;
  status.component = msg.component;
  status.state = msg.state;
  for (int i = 0; i < msg.num_counters; ++i) status.counters.emplace_back(msg.counter_names[i], msg.counter_values[i]);
  for (int i = 0; i < msg.num_timings; ++i) status.timings_ms.emplace_back(msg.timing_names[i], msg.timing_values_ms[i]);
  return status;
}

}  // namespace rgbdslam
