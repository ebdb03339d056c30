#include "rgbdslam/image/codec.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace rgbdslam {
namespace {

cv::Mat randomDepth(int width, int height) {
  cv::Mat depth(height, width, CV_16UC1);
  cv::randu(depth, 0, 30000);
  return depth;
}

TEST(Codec, DepthRoundTripIsExact) {
  const cv::Mat depth = randomDepth(64, 48);
  const auto bytes = compressDepth(depth);
  auto back = decompressDepth(bytes.data(), bytes.size(), 64, 48);
  ASSERT_TRUE(back) << back.error();
  EXPECT_EQ(cv::norm(depth, *back, cv::NORM_INF), 0.0);
}

TEST(Codec, TruncatedOrWrongSizedDepthIsAnError) {
  const cv::Mat depth = randomDepth(64, 48);
  const auto bytes = compressDepth(depth);
  EXPECT_FALSE(decompressDepth(bytes.data(), bytes.size() / 2, 64, 48));
  EXPECT_FALSE(decompressDepth(bytes.data(), bytes.size(), 64, 47));
  EXPECT_FALSE(decompressDepth(bytes.data(), bytes.size(), 64, 49));
  const std::vector<uint8_t> garbage(100, 0xAB);
  EXPECT_FALSE(decompressDepth(garbage.data(), garbage.size(), 64, 48));
}

// A wall 1-6 m away read by a Kinect-like sensor: sigma = a z^2, stored in millimetres, and
// a band without readings.
cv::Mat noisyWall(int width, int height, double a) {
  cv::Mat depth(height, width, CV_16UC1);
  cv::RNG rng(7);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const double z = 1.0 + 5.0 * u / width;
      depth.at<uint16_t>(v, u) = v % 16 < 2 ? 0 : static_cast<uint16_t>(std::lround(1000 * (z + rng.gaussian(a * z * z))));
    }
  }
  return depth;
}

TEST(Codec, InverseDepthStaysWithinHalfAStepAndKeepsMissingReadings) {
  const double a = 3.331e-3, step = 0.25 * a;
  const cv::Mat depth = noisyWall(160, 120, a);
  const auto bytes = compressInverseDepth(depth, 1000.0, step);
  auto back = decompressInverseDepth(bytes.data(), bytes.size(), 160, 120, 1000.0);
  ASSERT_TRUE(back) << back.error();
  double worst = 0;
  for (int v = 0; v < 120; ++v) {
    for (int u = 0; u < 160; ++u) {
      const int raw = depth.at<uint16_t>(v, u), out = back->at<uint16_t>(v, u);
      ASSERT_EQ(raw == 0, out == 0) << u << "," << v;
      if (raw == 0) continue;
      // Half a step in inverse depth, and the millimetre of the decoded reading.
      const double z = raw / 1000.0, z_out = out / 1000.0;
      worst = std::max(worst, std::abs(1 / z_out - 1 / z) / (step / 2 + 0.0005 / (z_out * z_out)));
    }
  }
  EXPECT_LE(worst, 1.0 + 1e-9);
  EXPECT_LT(bytes.size(), compressDepth(depth, 6).size() * 3 / 4) << "a quarter smaller than zlib at least";
}

TEST(Codec, AnInverseStepTooFineForTheNearestReadingIsWidened) {
  cv::Mat depth(8, 8, CV_16UC1, cv::Scalar(300));  // 0.3 m
  depth.at<uint16_t>(3, 3) = 4000;
  const auto bytes = compressInverseDepth(depth, 1000.0, 1e-9);
  auto back = decompressInverseDepth(bytes.data(), bytes.size(), 8, 8, 1000.0);
  ASSERT_TRUE(back) << back.error();
  EXPECT_NEAR(back->at<uint16_t>(0, 0), 300, 1);
  EXPECT_NEAR(back->at<uint16_t>(3, 3), 4000, 200) << "a far reading is not clamped to the near one";
}

TEST(Codec, BadInverseDepthStreamsAreErrors) {
  const cv::Mat depth = noisyWall(64, 48, 3.331e-3);
  auto bytes = compressInverseDepth(depth, 1000.0, 1e-3);
  EXPECT_TRUE(decompressInverseDepth(bytes.data(), bytes.size(), 64, 48, 1000.0));
  EXPECT_FALSE(decompressInverseDepth(bytes.data(), bytes.size() - 1, 64, 48, 1000.0)) << "cut short";
  EXPECT_FALSE(decompressInverseDepth(bytes.data(), 3, 64, 48, 1000.0)) << "no step";
  EXPECT_FALSE(decompressInverseDepth(bytes.data(), bytes.size(), 64, 47, 1000.0)) << "another size";
  EXPECT_FALSE(decompressInverseDepth(bytes.data(), bytes.size(), 64, 48, 0.0)) << "no scale";
  auto longer = bytes;
  longer.push_back(0);
  EXPECT_FALSE(decompressInverseDepth(longer.data(), longer.size(), 64, 48, 1000.0)) << "trailing byte";
  for (float step : {0.0f, -1.0f, 11.0f, 1e-45f, std::numeric_limits<float>::quiet_NaN()}) {
    auto spoiled = bytes;
    uint32_t bits;
    std::memcpy(&bits, &step, 4);
    for (int i = 0; i < 4; ++i) spoiled[i] = static_cast<uint8_t>(bits >> (8 * i));
    EXPECT_FALSE(decompressInverseDepth(spoiled.data(), spoiled.size(), 64, 48, 1000.0)) << step;
  }
  const std::vector<uint8_t> garbage(100, 0xAB);
  EXPECT_FALSE(decompressInverseDepth(garbage.data(), garbage.size(), 64, 48, 1000.0));
}

TEST(Codec, JpegRoundTripIsClose) {
  cv::Mat image(48, 64, CV_8UC3);
  cv::randu(image, 0, 255);
  cv::GaussianBlur(image, image, cv::Size(5, 5), 2.0);
  const auto bytes = encodeJpeg(image, 95);
  auto back = decodeImage(bytes.data(), bytes.size(), 3, 64, 48);
  ASSERT_TRUE(back) << back.error();
  EXPECT_LT(cv::norm(image, *back, cv::NORM_L1) / image.total() / 3, 6.0);  // mean abs error [grey levels]; a wrong decode gives ~60
  EXPECT_FALSE(decodeImage(bytes.data(), bytes.size(), 3, 65, 48));  // size disagrees
  EXPECT_FALSE(decodeImage(bytes.data(), 10, 3, 64, 48));             // truncated
}

TEST(Codec, OptimalHuffmanTablesKeepThePixelsInFewerBytes) {
  cv::Mat image(480, 640, CV_8UC1);
  cv::randu(image, 0, 255);
  cv::GaussianBlur(image, image, cv::Size(5, 5), 1.5);
  for (int quality : {30, 75}) {
    const auto standard = encodeJpeg(image, quality);
    const auto optimal = encodeJpeg(image, quality, /*optimal_huffman=*/true);
    EXPECT_LT(optimal.size(), standard.size()) << quality;
    auto a = decodeImage(standard.data(), standard.size(), 1, 640, 480);
    auto b = decodeImage(optimal.data(), optimal.size(), 1, 640, 480);
    ASSERT_TRUE(a && b) << quality;
    EXPECT_EQ(cv::norm(*a, *b, cv::NORM_INF), 0.0) << quality;  // the same coefficients
  }
}

TEST(Codec, PngRoundTripIsExact) {
  cv::Mat grey(48, 64, CV_8UC1);
  cv::randu(grey, 0, 255);
  const auto bytes = encodePng(grey);
  auto back = decodeImage(bytes.data(), bytes.size(), 1, 64, 48);
  ASSERT_TRUE(back) << back.error();
  EXPECT_EQ(cv::norm(grey, *back, cv::NORM_INF), 0.0);
}


// A textured 640x480 image, as a camera's: noise blurred to the scale of corners.
cv::Mat codecTestImage(int type, uint64_t seed) {
  cv::Mat image(480, 640, type);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, CV_MAT_DEPTH(type) == CV_16U ? 40000 : 256);
  cv::GaussianBlur(image, image, cv::Size(5, 5), 1.5);
  return image;
}

// Each way of reading an image, and imgcodecs' flag for the same.
const std::pair<ImageRead, int> kCodecReads[] = {
    {ImageRead::kGrey, cv::IMREAD_GRAYSCALE}, {ImageRead::kColour, cv::IMREAD_COLOR}, {ImageRead::kAsStored, cv::IMREAD_UNCHANGED}};

// The codec went from OpenCV's imgcodecs to libjpeg-turbo and libpng with imgcodecs'
// settings: the same JPEG bytes, and every image decodes to the same pixels either way (a
// cold keyframe's JPEG is decoded when it is thawed, so a pixel off would change tracks).
TEST(Codec, JpegAndPngAgreeWithOpenCvsImgcodecs) {
  for (const int type : {CV_8UC1, CV_8UC3}) {
    const cv::Mat image = codecTestImage(type, 11 + type);
    for (const int quality : {30, 75, 95}) {
      for (const bool optimal : {false, true}) {
        SCOPED_TRACE("type " + std::to_string(type) + ", quality " + std::to_string(quality) +
                     (optimal ? ", optimal Huffman" : ""));
        const std::vector<uint8_t> ours = encodeJpeg(image, quality, optimal);
        std::vector<uint8_t> theirs;
        ASSERT_TRUE(cv::imencode(".jpg", image, theirs,
                                 {cv::IMWRITE_JPEG_QUALITY, quality, cv::IMWRITE_JPEG_OPTIMIZE, optimal ? 1 : 0}));
        EXPECT_EQ(ours, theirs);
        for (const auto& [read, flag] : kCodecReads) {
          const auto decoded = decodeImage(ours.data(), ours.size(), read, image.size());
          ASSERT_TRUE(decoded) << decoded.error();
          const cv::Mat want = cv::imdecode(ours, flag);
          ASSERT_EQ(decoded->type(), want.type());
          EXPECT_EQ(cv::norm(*decoded, want, cv::NORM_INF), 0.0);
        }
      }
    }
  }
  // A progressive JPEG (a camera's or a file's; ours are baseline) within the decoder's
  // memory and scan limits.
  for (const int type : {CV_8UC1, CV_8UC3}) {
    std::vector<uint8_t> progressive;
    ASSERT_TRUE(cv::imencode(".jpg", codecTestImage(type, 21), progressive, {cv::IMWRITE_JPEG_PROGRESSIVE, 1}));
    const auto decoded = decodeImage(progressive.data(), progressive.size(), ImageRead::kAsStored, cv::Size(640, 480));
    ASSERT_TRUE(decoded) << decoded.error();
    EXPECT_EQ(cv::norm(*decoded, cv::imdecode(progressive, cv::IMREAD_UNCHANGED), cv::NORM_INF), 0.0);
  }
  // PNG: grey and BGR at 8 bits, depth at 16 (TUM's files), each read as imgcodecs reads it.
  for (const int type : {CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1}) {
    SCOPED_TRACE("PNG type " + std::to_string(type));
    const cv::Mat image = codecTestImage(type, 31 + type);
    const std::vector<uint8_t> ours = encodePng(image);
    const cv::Mat theirs = cv::imdecode(ours, cv::IMREAD_UNCHANGED);
    ASSERT_EQ(theirs.type(), type);
    EXPECT_EQ(cv::norm(theirs, image, cv::NORM_INF), 0.0);  // a standard PNG, lossless
    std::vector<uint8_t> png;
    ASSERT_TRUE(cv::imencode(".png", image, png));
    for (const auto& [read, flag] : kCodecReads) {
      const auto decoded = decodeImage(png.data(), png.size(), read, image.size());
      ASSERT_TRUE(decoded) << decoded.error();
      const cv::Mat want = cv::imdecode(png, flag);
      ASSERT_EQ(decoded->type(), want.type()) << static_cast<int>(read);
      EXPECT_EQ(cv::norm(*decoded, want, cv::NORM_INF), 0.0) << static_cast<int>(read);
    }
  }
}

// A PNG written by hand (no filter, one IDAT), for the colour types and bit depths that
// OpenCV's encoder does not write: rows of raw bytes as the format packs them.
std::vector<uint8_t> handMadePng(int width, int height, int bit_depth, int colour_type,
                                 const std::vector<std::vector<uint8_t>>& rows, const std::vector<uint8_t>& palette = {},
                                 const std::vector<uint8_t>& transparent = {}) {
  std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  const auto chunk = [&png](const char* type, const std::vector<uint8_t>& body) {
    const uint32_t n = static_cast<uint32_t>(body.size());
    for (int s : {24, 16, 8, 0}) png.push_back(static_cast<uint8_t>(n >> s));
    std::vector<uint8_t> typed(type, type + 4);
    typed.insert(typed.end(), body.begin(), body.end());
    png.insert(png.end(), typed.begin(), typed.end());
    const uint32_t crc = static_cast<uint32_t>(crc32(0, typed.data(), static_cast<uInt>(typed.size())));
    for (int s : {24, 16, 8, 0}) png.push_back(static_cast<uint8_t>(crc >> s));
  };
  std::vector<uint8_t> header;
  for (uint32_t v : {static_cast<uint32_t>(width), static_cast<uint32_t>(height)}) {
    for (int s : {24, 16, 8, 0}) header.push_back(static_cast<uint8_t>(v >> s));
  }
  header.insert(header.end(), {static_cast<uint8_t>(bit_depth), static_cast<uint8_t>(colour_type), 0, 0, 0});
  chunk("IHDR", header);
  if (!palette.empty()) chunk("PLTE", palette);
  if (!transparent.empty()) chunk("tRNS", transparent);
  std::vector<uint8_t> raw;
  for (const auto& row : rows) {
    raw.push_back(0);  // filter: none
    raw.insert(raw.end(), row.begin(), row.end());
  }
  std::vector<uint8_t> deflated(compressBound(static_cast<uLong>(raw.size())));
  uLongf n = static_cast<uLongf>(deflated.size());
  compress(deflated.data(), &n, raw.data(), static_cast<uLong>(raw.size()));
  deflated.resize(n);
  chunk("IDAT", deflated);
  chunk("IEND", {});
  return png;
}

// Every PNG colour type and bit depth, each way of reading it, as imgcodecs reads it.
TEST(Codec, EveryKindOfPngReadsAsImgcodecsReadsIt) {
  constexpr int kW = 16, kH = 4;
  std::mt19937 rng(7);
  const auto rows = [&rng](size_t bytes) {
    std::vector<std::vector<uint8_t>> out(kH, std::vector<uint8_t>(bytes));
    for (auto& row : out) {
      for (auto& b : row) b = static_cast<uint8_t>(rng());
    }
    return out;
  };
  std::vector<uint8_t> palette(3 * 16);
  for (auto& b : palette) b = static_cast<uint8_t>(rng());
  struct Kind {
    const char* name;
    std::vector<uint8_t> png;
  };
  const std::vector<Kind> kinds = {
      {"grey 1-bit", handMadePng(kW, kH, 1, 0, rows(kW / 8))},
      {"grey 4-bit", handMadePng(kW, kH, 4, 0, rows(kW / 2))},
      {"grey 8-bit, a transparent grey", handMadePng(kW, kH, 8, 0, rows(kW), {}, {0, 7})},
      {"grey 16-bit, a transparent grey", handMadePng(kW, kH, 16, 0, rows(2 * kW), {}, {1, 2})},
      {"grey and alpha, 8-bit", handMadePng(kW, kH, 8, 4, rows(2 * kW))},
      {"RGB 16-bit", handMadePng(kW, kH, 16, 2, rows(6 * kW))},
      {"RGB 8-bit, a transparent colour", handMadePng(kW, kH, 8, 2, rows(3 * kW), {}, {0, 1, 0, 2, 0, 3})},
      {"palette 4-bit", handMadePng(kW, kH, 4, 3, rows(kW / 2), palette)},
      {"palette 8-bit, transparent entries", handMadePng(kW, kH, 8, 3, std::vector<std::vector<uint8_t>>(kH, std::vector<uint8_t>(kW, 5)), palette, {0, 128, 255})},
  };
  for (const Kind& kind : kinds) {
    for (const auto& [read, flag] : kCodecReads) {
      SCOPED_TRACE(std::string(kind.name) + ", read " + std::to_string(static_cast<int>(read)));
      const cv::Mat want = cv::imdecode(kind.png, flag);
      ASSERT_FALSE(want.empty());
      const auto decoded = decodeImage(kind.png.data(), kind.png.size(), read, cv::Size(kW, kH));
      ASSERT_TRUE(decoded) << decoded.error();
      ASSERT_EQ(decoded->type(), want.type());
      EXPECT_EQ(cv::norm(*decoded, want, cv::NORM_INF), 0.0);
    }
  }
}

// Bad input gets an error, not a made-up image: a JPEG or PNG cut anywhere (imgcodecs
// returned a cut JPEG whole), a PNG with a changed byte (its CRC), a JPEG whose header walk
// meets a stuffed zero where a marker should be (a decoder skips it and may find another
// frame header than the walk did). A changed byte inside a JPEG's coded data may decode
// without complaint: JPEG has no checksum.
TEST(Codec, CutOrCorruptJpegAndPngAreErrors) {
  const cv::Mat image = codecTestImage(CV_8UC1, 5);
  for (const auto& bytes : {encodeJpeg(image, 75), encodePng(image)}) {
    for (const double keep : {0.05, 0.5, 0.9, 0.999}) {
      const size_t cut = static_cast<size_t>(keep * bytes.size());
      const auto refused = decodeImage(bytes.data(), cut, ImageRead::kGrey, image.size());
      EXPECT_FALSE(refused) << "kept " << cut << " of " << bytes.size();
    }
  }
  std::vector<uint8_t> png = encodePng(image);
  png[png.size() / 2] ^= 0x55;  // inside the image data: its CRC no longer holds
  const auto refused = decodeImage(png.data(), png.size(), ImageRead::kGrey, image.size());
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().find("corrupt PNG"), std::string::npos) << refused.error();
  std::vector<uint8_t> jpeg = encodeJpeg(image, 75);
  jpeg.insert(jpeg.begin() + 2, {0xFF, 0x00, 0x00, 0x04, 0x00, 0x00});
  EXPECT_FALSE(encodedImageSize(jpeg.data(), jpeg.size()));
  EXPECT_FALSE(decodeImage(jpeg.data(), jpeg.size(), ImageRead::kGrey, image.size()));
}

// A file of synth-write or a plot: written whole, read back the same.
TEST(Codec, APngFileReadsBackTheSame) {
  const cv::Mat depth = codecTestImage(CV_16UC1, 9);
  const std::string path = ::testing::TempDir() + "codec_depth.png";
  ASSERT_TRUE(writePngFile(path, depth));
  EXPECT_EQ(cv::norm(cv::imread(path, cv::IMREAD_UNCHANGED), depth, cv::NORM_INF), 0.0);
  std::remove(path.c_str());
  EXPECT_FALSE(writePngFile("/nonexistent-directory/x.png", depth));
}

// The offset of a JPEG's frame header (SOFn) marker, found by the same walk a decoder does.
size_t jpegFrameHeader(const std::vector<uint8_t>& jpeg) {
  size_t at = 2;
  while (at + 4 <= jpeg.size()) {
    const uint8_t marker = jpeg[at + 1];
    if (marker >= 0xC0 && marker <= 0xC3) return at;
    at += 2 + ((jpeg[at + 2] << 8) | jpeg[at + 3]);
  }
  return 0;
}

TEST(Codec, ReadsTheDeclaredSizeWithoutDecoding) {
  cv::Mat image(48, 64, CV_8UC3, cv::Scalar(10, 20, 30));
  for (const auto& bytes : {encodeJpeg(image, 90), encodePng(image)}) {
    const auto size = encodedImageSize(bytes.data(), bytes.size());
    ASSERT_TRUE(size) << size.error();
    EXPECT_EQ(*size, cv::Size(64, 48));
    EXPECT_FALSE(encodedImageSize(bytes.data(), 6));  // cut off before the size
  }
  std::vector<uint8_t> bmp;
  cv::imencode(".bmp", image, bmp);
  const auto refused = decodeImage(bmp.data(), bmp.size(), 3, 64, 48);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().find("neither JPEG nor PNG"), std::string::npos) << refused.error();
}

// A few bytes of JPEG header may declare a 30000x30000 image: decoding it would allocate
// 2.7 GB before the size is compared (an out-of-memory the fuzzer found in an LCM log). The
// header is read first, so it is refused without the allocation.
TEST(Codec, AHeaderDeclaringAHugeImageIsRefusedBeforeDecoding) {
  auto bytes = encodeJpeg(cv::Mat(48, 64, CV_8UC1, cv::Scalar(7)), 90);
  const size_t sof = jpegFrameHeader(bytes);
  ASSERT_GT(sof, 0u);
  for (size_t i : {sof + 5, sof + 7}) {  // height, width: big-endian 16 bits each
    bytes[i] = 30000 >> 8;
    bytes[i + 1] = 30000 & 0xFF;
  }
  const auto size = encodedImageSize(bytes.data(), bytes.size());
  ASSERT_TRUE(size) << size.error();
  EXPECT_EQ(*size, cv::Size(30000, 30000));
  const auto refused = decodeImage(bytes.data(), bytes.size(), 1, 64, 48);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().find("header says 30000x30000, expected 64x48"), std::string::npos) << refused.error();

  auto png = encodePng(cv::Mat(48, 64, CV_8UC1, cv::Scalar(7)));
  png[16] = png[20] = 0x7F;  // width and height 2^31 - ...
  EXPECT_FALSE(encodedImageSize(png.data(), png.size()));
  EXPECT_FALSE(decodeImage(png.data(), png.size(), 1, 64, 48));
}

}  // namespace
}  // namespace rgbdslam
