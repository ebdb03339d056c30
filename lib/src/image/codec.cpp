#include "rgbdslam/image/codec.h"

#include <zlib.h>

#include <algorithm>
#include <opencv2/imgcodecs.hpp>
#include <string>

namespace rgbdslam {

std::vector<uint8_t> encodeJpeg(const cv::Mat& image, int quality) {
  std::vector<uint8_t> out;
  cv::imencode(".jpg", image, out, {cv::IMWRITE_JPEG_QUALITY, quality});
  return out;
}

std::vector<uint8_t> encodePng(const cv::Mat& image) {
  std::vector<uint8_t> out;
  cv::imencode(".png", image, out, {cv::IMWRITE_PNG_COMPRESSION, 1});
  return out;
}

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

Expected<cv::Mat> decodeImage(const uint8_t* data, size_t size, int imread_flags, cv::Size expected) {
  if (size == 0) return Error{"empty compressed image"};
  // The header first: a few bytes may declare a gigapixel image, which the decoder would
  // allocate before anything else is checked.
  const Expected<cv::Size> declared = encodedImageSize(data, size);
  if (!declared) return Error{declared.error()};
  if (*declared != expected) {
    return Error{"image header says " + std::to_string(declared->width) + "x" + std::to_string(declared->height) +
                 ", expected " + std::to_string(expected.width) + "x" + std::to_string(expected.height)};
  }
  cv::Mat image;
  try {
    const cv::Mat buffer(1, static_cast<int>(size), CV_8UC1, const_cast<uint8_t*>(data));
    image = cv::imdecode(buffer, imread_flags);
  } catch (const cv::Exception& e) {
    return Error{"image does not decode: " + e.msg};
  }
  if (image.empty()) return Error{"image does not decode (corrupt or truncated)"};
  if (image.size() != expected) {
    return Error{"decoded image is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) + ", expected " +
                 std::to_string(expected.width) + "x" + std::to_string(expected.height)};
  }
  return image;
}

Expected<cv::Mat> decodeImage(const uint8_t* data, size_t size, int channels, int width, int height) {
  return decodeImage(data, size, channels == 1 ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR, cv::Size(width, height));
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
