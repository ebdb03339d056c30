#include "rgbdslam/image/codec.h"

#include <zlib.h>

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

Expected<cv::Mat> decodeImage(const uint8_t* data, size_t size, int channels, int width,
                              int height) {
  if (size == 0) return Error{"empty compressed image"};
  cv::Mat image;
  try {
    const cv::Mat buffer(1, static_cast<int>(size), CV_8UC1, const_cast<uint8_t*>(data));
    image = cv::imdecode(buffer, channels == 1 ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
  } catch (const cv::Exception& e) {
    return Error{"image does not decode: " + e.msg};
  }
  if (image.empty()) return Error{"image does not decode (corrupt or truncated)"};
  if (image.cols != width || image.rows != height) {
    return Error{"decoded image is " + std::to_string(image.cols) + "x" +
                 std::to_string(image.rows) + ", expected " + std::to_string(width) + "x" +
                 std::to_string(height)};
  }
  return image;
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
