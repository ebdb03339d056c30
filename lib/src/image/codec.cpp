#include "rgbdslam/image/codec.h"

#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

namespace rgbdslam {

namespace {

uint32_t bigEndian(const uint8_t* in, int bytes) {
  uint32_t value = 0;
  for (int i = 0; i < bytes; ++i) value = (value << 8) | in[i];
  return value;
}

// The frame header (SOF0..SOF15 but DHT, JPG and DAC) of a JPEG stream: its size. Markers
// before it are walked by their lengths; a scan or the end before a frame header is an error.
Expected<cv::Size> jpegSize(const uint8_t* data, size_t size) {
  size_t at = 2;  // after SOI
  while (at + 4 <= size) {
    if (data[at] != 0xFF) return Error{"corrupt JPEG (no marker at byte " + std::to_string(at) + ")"};
    const uint8_t marker = data[at + 1];
    if (marker == 0xFF) {  // fill byte
      ++at;
      continue;
    }
    // FF 00 is a stuffed zero, not a marker: a decoder skips it as stray data and reads on
    // (a header walk that took it for a segment could be led past the frame header used).
    if (marker == 0x00) return Error{"corrupt JPEG (no marker at byte " + std::to_string(at) + ")"};
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD8)) {  // no length: TEM, RSTn, SOI
      at += 2;
      continue;
    }
    if (marker == 0xD9 || marker == 0xDA) break;  // EOI or a scan before any frame header
    const size_t length = bigEndian(data + at + 2, 2);
    if (length < 2) return Error{"corrupt JPEG (a segment of length " + std::to_string(length) + ")"};
    const bool frame_header = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (frame_header) {
      if (length < 8 || at + 9 > size) break;
      const int height = static_cast<int>(bigEndian(data + at + 5, 2));
      const int width = static_cast<int>(bigEndian(data + at + 7, 2));
      return cv::Size(width, height);
    }
    at += 2 + length;
  }
  return Error{"JPEG without a frame header (truncated or corrupt)"};
}

}  // namespace

Expected<cv::Size> encodedImageSize(const uint8_t* data, size_t size) {
  static constexpr uint8_t kPng[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (size >= 2 && data[0] == 0xFF && data[1] == 0xD8) return jpegSize(data, size);
  if (size >= sizeof kPng && std::equal(kPng, kPng + sizeof kPng, data)) {
    // The first chunk must be IHDR: 4 bytes length, "IHDR", 4 bytes width, 4 bytes height.
    if (size < 24 || !std::equal(data + 12, data + 16, "IHDR")) return Error{"PNG without an IHDR chunk"};
    const uint32_t width = bigEndian(data + 16, 4), height = bigEndian(data + 20, 4);
    if (width > kMaxDecodedSide || height > kMaxDecodedSide) {
      return Error{"PNG header says " + std::to_string(width) + "x" + std::to_string(height)};
    }
    return cv::Size(static_cast<int>(width), static_cast<int>(height));
  }
  return Error{"neither JPEG nor PNG (the only image encodings read)"};
}

std::vector<uint8_t> compressDepth(const cv::Mat& depth, int level) {
  CV_Assert(depth.type() == CV_16UC1);
  const cv::Mat contiguous = depth.isContinuous() ? depth : depth.clone();
  const uLong raw_size = static_cast<uLong>(contiguous.total() * 2);
  std::vector<uint8_t> out(compressBound(raw_size));
  uLongf out_size = out.size();
  const int rc = compress2(out.data(), &out_size, contiguous.data, raw_size, level);
  CV_Assert(rc == Z_OK);  // only fails on allocation or a bad level: programming errors
  out.resize(out_size);
  return out;
}

Expected<cv::Mat> decompressDepth(const uint8_t* data, size_t size, int width, int height) {
  if (width <= 0 || height <= 0) return Error{"bad depth image size"};
  cv::Mat depth(height, width, CV_16UC1);
  uLongf out_size = static_cast<uLongf>(depth.total() * 2);
  const uLongf expected_size = out_size;
  const int rc = uncompress(depth.data, &out_size, data, static_cast<uLong>(size));
  if (rc == Z_BUF_ERROR) return Error{"depth inflates to more than " + std::to_string(width) + "x" + std::to_string(height) + " pixels, or is truncated"};
  if (rc != Z_OK) return Error{"depth does not inflate (zlib error " + std::to_string(rc) + ")"};
  if (out_size != expected_size) {
    return Error{"depth inflates to " + std::to_string(out_size) + " bytes, expected " +
                 std::to_string(expected_size)};
  }
  return depth;
}

}  // namespace rgbdslam

namespace rgbdslam {
namespace {

// The median edge detector of LOCO-I (JPEG-LS) where the three neighbours hold readings,
// else the one valid neighbour (left first), else 0.
inline int predictInverse(int left, int above, int above_left) {
  if (left && above && above_left) {
    const int high = std::max(left, above), low = std::min(left, above);
    if (above_left >= high) return low;
    if (above_left <= low) return high;
    return left + above - above_left;
  }
  return left ? left : above;
}

inline uint16_t zigzag(uint16_t value, uint16_t prediction) {
  const int16_t r = static_cast<int16_t>(static_cast<uint16_t>(value - prediction));
  return static_cast<uint16_t>((static_cast<uint16_t>(r) << 1) ^ static_cast<uint16_t>(r >> 15));
}

inline uint16_t unzigzag(uint16_t code, uint16_t prediction) {
  const uint16_t r = static_cast<uint16_t>((code >> 1) ^ static_cast<uint16_t>(-(code & 1)));
  return static_cast<uint16_t>(prediction + r);
}

constexpr double kMinInverseStep = 1e-7, kMaxInverseStep = 10.0;  // [1/m]

bool validInverseStep(double step) {
  return std::isfinite(step) && step >= kMinInverseStep && step <= kMaxInverseStep;
}

// round(numerator / value) within [1, 65535], clamped in double (no overflow on any input).
inline uint16_t quotient16(double numerator, uint16_t value) {
  return static_cast<uint16_t>(std::lround(std::clamp(numerator / value, 1.0, 65535.0)));
}

}  // namespace

std::vector<uint8_t> compressInverseDepth(const cv::Mat& depth, double depth_scale, double inverse_step) {
  CV_Assert(depth.type() == CV_16UC1 && std::isfinite(inverse_step) && inverse_step > 0 && depth_scale > 0);
  inverse_step = std::clamp(inverse_step, kMinInverseStep, kMaxInverseStep);
  const int w = depth.cols, h = depth.rows;
  // The nearest reading must fit in 16 bits: a step too fine for it is widened (the stream
  // carries the step used).
  double nearest_raw = 65535;
  for (int v = 0; v < h; ++v) {
    const uint16_t* in = depth.ptr<uint16_t>(v);
    for (int u = 0; u < w; ++u) {
      if (in[u] != 0) nearest_raw = std::min<double>(nearest_raw, in[u]);
    }
  }
  inverse_step = std::min(kMaxInverseStep, std::max(inverse_step, depth_scale / (65535.0 * nearest_raw) * (1 + 1e-6)));
  inverse_step = static_cast<float>(inverse_step);  // as the stream carries it: both ends divide by the same step
  cv::Mat q(h, w, CV_16UC1);
  const double numerator = depth_scale / inverse_step;  // q = (scale / raw) / step
  for (int v = 0; v < h; ++v) {
    const uint16_t* in = depth.ptr<uint16_t>(v);
    uint16_t* out = q.ptr<uint16_t>(v);
    for (int u = 0; u < w; ++u) {
      out[u] = in[u] == 0 ? 0 : quotient16(numerator, in[u]);
    }
  }
  const size_t n = static_cast<size_t>(w) * h;
  std::vector<uint8_t> planes(2 * n);
  for (int v = 0; v < h; ++v) {
    const uint16_t* row = q.ptr<uint16_t>(v);
    const uint16_t* up = v > 0 ? q.ptr<uint16_t>(v - 1) : nullptr;
    for (int u = 0; u < w; ++u) {
      const int prediction = predictInverse(u > 0 ? row[u - 1] : 0, up ? up[u] : 0, up && u > 0 ? up[u - 1] : 0);
      const uint16_t code = zigzag(row[u], static_cast<uint16_t>(prediction));
      const size_t i = static_cast<size_t>(v) * w + u;
      planes[i] = static_cast<uint8_t>(code & 0xff);
      planes[n + i] = static_cast<uint8_t>(code >> 8);
    }
  }
  std::vector<uint8_t> out(4 + ZSTD_compressBound(planes.size()));
  const float step = static_cast<float>(inverse_step);
  uint32_t bits;
  std::memcpy(&bits, &step, 4);
  for (int i = 0; i < 4; ++i) out[i] = static_cast<uint8_t>(bits >> (8 * i));
  const size_t packed = ZSTD_compress(out.data() + 4, out.size() - 4, planes.data(), planes.size(), 9);
  CV_Assert(!ZSTD_isError(packed));  // only on allocation failure: the bound is enough
  out.resize(4 + packed);
  return out;
}

Expected<cv::Mat> decompressInverseDepth(const uint8_t* data, size_t size, int width, int height,
                                         double depth_scale) {
  if (width <= 0 || height <= 0) return Error{"bad depth image size"};
  if (!(depth_scale > 0) || !std::isfinite(depth_scale)) return Error{"bad depth scale"};
  if (size < 4) return Error{"inverse depth stream of " + std::to_string(size) + " bytes has no step"};
  uint32_t bits = 0;
  for (int i = 0; i < 4; ++i) bits |= static_cast<uint32_t>(data[i]) << (8 * i);
  float step;
  std::memcpy(&step, &bits, 4);
  if (!validInverseStep(step)) return Error{"inverse depth step " + std::to_string(step) + " outside [1e-7, 10] 1/m"};
  const size_t n = static_cast<size_t>(width) * height;
  const unsigned long long declared = ZSTD_getFrameContentSize(data + 4, size - 4);
  if (declared == ZSTD_CONTENTSIZE_ERROR) return Error{"inverse depth is not a zstd frame"};
  if (declared != 2 * n) {
    return Error{"inverse depth declares " + (declared == ZSTD_CONTENTSIZE_UNKNOWN ? std::string("no") : std::to_string(declared)) +
                 " bytes, " + std::to_string(width) + "x" + std::to_string(height) + " needs " + std::to_string(2 * n)};
  }
  std::vector<uint8_t> planes(2 * n);
  const size_t got = ZSTD_decompress(planes.data(), planes.size(), data + 4, size - 4);
  if (ZSTD_isError(got)) return Error{std::string("inverse depth does not decompress: ") + ZSTD_getErrorName(got)};
  if (got != planes.size()) return Error{"inverse depth decompresses to " + std::to_string(got) + " bytes, expected " + std::to_string(planes.size())};
  cv::Mat q(height, width, CV_16UC1);
  for (int v = 0; v < height; ++v) {
    uint16_t* row = q.ptr<uint16_t>(v);
    const uint16_t* up = v > 0 ? q.ptr<uint16_t>(v - 1) : nullptr;
    for (int u = 0; u < width; ++u) {
      const int prediction = predictInverse(u > 0 ? row[u - 1] : 0, up ? up[u] : 0, up && u > 0 ? up[u - 1] : 0);
      const size_t i = static_cast<size_t>(v) * width + u;
      row[u] = unzigzag(static_cast<uint16_t>(planes[i] | (planes[n + i] << 8)), static_cast<uint16_t>(prediction));
    }
  }
  cv::Mat depth(height, width, CV_16UC1);
  const double numerator = depth_scale / step;  // raw = scale / (q * step)
  for (int v = 0; v < height; ++v) {
    const uint16_t* in = q.ptr<uint16_t>(v);
    uint16_t* out = depth.ptr<uint16_t>(v);
    for (int u = 0; u < width; ++u) {
      out[u] = in[u] == 0 ? 0 : quotient16(numerator, in[u]);
    }
  }
  return depth;
}

}  // namespace rgbdslam
