#pragma once
// Image encodings used on the wire and on disk: JPEG/PNG for 8-bit images (and PNG for
// 16-bit depth files), zlib (deflate) for 16-bit depth, and for keyframe depth on the radio
// link quantised inverse depth with zstd. Decoders validate sizes and report errors instead
// of crashing. JPEG and PNG go through libjpeg-turbo and libpng (codec_jpeg_png.cpp says
// why not OpenCV's imgcodecs).
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "rgbdslam/util/expected.h"

namespace rgbdslam {

// No encoded image is read with a side beyond this (PNG allows 2^31 - 1).
constexpr uint32_t kMaxDecodedSide = 65535;  // [px], JPEG's own limit

// 8-bit grey or BGR image -> JPEG bytes; quality in [1, 100]. optimal_huffman: Huffman
// tables made for this image (libjpeg's optimize_coding) instead of the standard ones: the
// same decoded pixels in fewer bytes, for a second pass over the coefficients. Measured on
// 30 grey frames of synth:corridor and 20 of TUM fr3/teddy (640x480): 7 % / 4 % fewer bytes
// at quality 75, 20 % / 12 % at quality 30, for +0.3-0.5 ms per image (0.4 -> 0.7-1.0 ms).
// For what crosses the radio link; frames on the host's own network keep the faster pass.
std::vector<uint8_t> encodeJpeg(const cv::Mat& image, int quality, bool optimal_huffman = false);
// 8- or 16-bit grey, BGR or BGRA image -> PNG bytes (lossless; zlib level 1).
std::vector<uint8_t> encodePng(const cv::Mat& image);
// encodePng into a file (replaced if it exists).
Status writePngFile(const std::string& path, const cv::Mat& image);
// The size a JPEG or PNG stream declares in its header, read without decoding; an error for
// any other encoding or a header that is cut off.
Expected<cv::Size> encodedImageSize(const uint8_t* data, size_t size);
// How an image is decoded: 8-bit grey (colour by Rec. 601 luma), 8-bit BGR, or as stored
// (its bit depth; grey, BGR or BGRA).
enum class ImageRead { kGrey, kColour, kAsStored };
// JPEG/PNG bytes -> image, refused before decoding unless its header declares the expected
// size (so a hostile header cannot make the decoder allocate more than the expected image).
// A corrupt or truncated stream is an error, never an image with made-up rows.
Expected<cv::Mat> decodeImage(const uint8_t* data, size_t size, ImageRead read, cv::Size expected);
// JPEG/PNG bytes -> image with 'channels' (1 grey, 3 BGR), checked against the expected size.
Expected<cv::Mat> decodeImage(const uint8_t* data, size_t size, int channels, int width,
                              int height);

// CV_16UC1 depth -> zlib stream of its little-endian rows; level in [0, 9].
std::vector<uint8_t> compressDepth(const cv::Mat& depth, int level = 1);
// zlib stream -> CV_16UC1 of the given size; an error if it does not inflate to exactly
// width*height*2 bytes.
Expected<cv::Mat> decompressDepth(const uint8_t* data, size_t size, int width, int height);

// Depth for the link, in the sensor's own terms: a Kinect reading's noise is uniform in
// inverse depth (sigma_z = a z^2, noise_model.h, is sigma_(1/z) = a), so each reading is
// stored as q = round(1 / (z * inverse_step)), a step that is a fixed fraction of the noise at
// every depth (inverse_step = f * a: the rounding adds f / sqrt(12) sigma, 0.07 sigma at
// f = 0.25). q is predicted from its neighbours (left, above, above-left: the median edge
// predictor of LOCO-I, or the one valid neighbour), the residuals zigzag-coded, their low
// and high bytes in two planes, zstd. Stream: inverse_step as a little-endian float32 [1/m],
// then one zstd frame of width*height*2 bytes. A step too fine for the nearest reading
// (q above 65535: nearer than 1.8 cm at a = 3.331e-3, f = 0.25) is widened until it fits;
// the stream carries the step used.
// Measured on keyframe depth at every 4th pixel and row (160x120; docs/open_work.md):
// synthetic corridor 10.8 kB with zlib-6 -> 7.1 kB, flight 7.8 -> 6.0 kB, TUM teddy
// 10.8 -> 7.0 kB (f 0.5).
// CV_16UC1 raw depth (0: no reading) at depth_scale units per metre -> stream;
// inverse_step > 0 [1/m], taken within [1e-7, 10].
std::vector<uint8_t> compressInverseDepth(const cv::Mat& depth, double depth_scale, double inverse_step);
// Stream -> CV_16UC1 of the given size at depth_scale units per metre (0: no reading);
// an error for a stream that is cut short, too long, declares another size or a step outside
// [1e-7, 10] [1/m].
Expected<cv::Mat> decompressInverseDepth(const uint8_t* data, size_t size, int width, int height,
                                         double depth_scale);

}  // namespace rgbdslam
