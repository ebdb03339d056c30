#pragma once
// Image encodings used on the wire and on disk: JPEG/PNG for 8-bit images, zlib (deflate)
// for 16-bit depth. Decoders validate sizes and report errors instead of crashing.
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "rgbdslam/util/expected.h"

namespace rgbdslam {

// No encoded image is read with a side beyond this (PNG allows 2^31 - 1).
constexpr uint32_t kMaxDecodedSide = 65535;  // [px], JPEG's own limit

// 8-bit grey or BGR image -> JPEG bytes; quality in [1, 100].
std::vector<uint8_t> encodeJpeg(const cv::Mat& image, int quality);
// 8-bit image -> PNG bytes (lossless).
std::vector<uint8_t> encodePng(const cv::Mat& image);
// The size a JPEG or PNG stream declares in its header, read without decoding; an error for
// any other encoding or a header that is cut off.
Expected<cv::Size> encodedImageSize(const uint8_t* data, size_t size);
// JPEG/PNG bytes -> image decoded with cv::imread flags, refused before decoding unless its
// header declares the expected size (so a hostile header cannot make the decoder allocate
// more than the expected image).
Expected<cv::Mat> decodeImage(const uint8_t* data, size_t size, int imread_flags, cv::Size expected);
// JPEG/PNG bytes -> image with 'channels' (1 grey, 3 BGR), checked against the expected size.
Expected<cv::Mat> decodeImage(const uint8_t* data, size_t size, int channels, int width,
                              int height);

// CV_16UC1 depth -> zlib stream of its little-endian rows; level in [0, 9].
std::vector<uint8_t> compressDepth(const cv::Mat& depth, int level = 1);
// zlib stream -> CV_16UC1 of the given size; an error if it does not inflate to exactly
// width*height*2 bytes.
Expected<cv::Mat> decompressDepth(const uint8_t* data, size_t size, int width, int height);

}  // namespace rgbdslam
