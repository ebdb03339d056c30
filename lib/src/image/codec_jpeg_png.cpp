// codec.h's JPEG and PNG coding, through libjpeg-turbo and libpng directly.
//
// Why not OpenCV's imgcodecs: Debian builds it with every image format it knows (GDAL,
// GDCM, OpenEXR, ...), and linking it puts 150 libraries into a process: 38 MB of resident
// memory before the program does anything (a program that only links it, measured against
// one that does not; in rgbd-tracker most of its 57 MB of resident library pages). The
// suite uses two formats, and the onboard tracker's memory budget is 150 MB
// (docs/open_work.md, session 42). The settings are OpenCV's own (jpeg_set_defaults,
// baseline quality tables, optional optimised Huffman tables, islow DCT; PNG at zlib level
// 1), so a JPEG's bytes and every decoded pixel are as before (tests/image/test_codec.cpp
// compares them with imgcodecs).
//
// Both libraries report errors by longjmp to the call's setjmp. Everything written after
// the setjmp lives in a heap-allocated state (an automatic variable changed between setjmp
// and longjmp would be indeterminate), and no object with a destructor is left between the
// two: the jumps cross only the libraries' C frames.
#include <algorithm>
#include <csetjmp>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>

#include "rgbdslam/image/codec.h"

// After <cstdio> and <cstddef>: jpeglib.h uses FILE and size_t without including them.
#include <jpeglib.h>
#include <png.h>

namespace rgbdslam {
namespace {

// ---- JPEG ----

struct JpegErrors {
  jpeg_error_mgr manager;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX] = "";
  int corrupt = 0;  // warnings: corrupt or truncated data libjpeg went on past
};

void jpegFail(j_common_ptr info) {
  auto* errors = reinterpret_cast<JpegErrors*>(info->err);
  (*info->err->format_message)(info, errors->message);
  std::longjmp(errors->jump, 1);
}

// libjpeg calls this with level -1 for a warning (it decodes on, filling what is missing
// with grey); levels >= 0 are trace messages. A warning makes the image an error here.
void jpegMessage(j_common_ptr info, int level) {
  if (level >= 0) return;
  auto* errors = reinterpret_cast<JpegErrors*>(info->err);
  if (errors->corrupt++ == 0) (*info->err->format_message)(info, errors->message);
}

JpegErrors* useErrors(JpegErrors* errors) {
  jpeg_std_error(&errors->manager);
  errors->manager.error_exit = jpegFail;
  errors->manager.emit_message = jpegMessage;
  return errors;
}

struct JpegEncoding {
  jpeg_compress_struct info;
  JpegErrors errors;
  unsigned char* bytes = nullptr;  // jpeg_mem_dest's buffer (malloc)
  unsigned long size = 0;
};

struct JpegDecoding {
  jpeg_decompress_struct info;
  JpegErrors errors;
  cv::Mat image;
};

Expected<cv::Mat> decodeJpeg(const uint8_t* data, size_t size, ImageRead read) {
  auto state = std::make_unique<JpegDecoding>();
  state->info.err = &useErrors(&state->errors)->manager;
  jpeg_create_decompress(&state->info);
  if (setjmp(state->errors.jump)) {
    jpeg_destroy_decompress(&state->info);
    return Error{std::string("corrupt JPEG (") + state->errors.message + ")"};
  }
  jpeg_mem_src(&state->info, data, static_cast<unsigned long>(size));
  jpeg_read_header(&state->info, TRUE);
  const int components = state->info.num_components;
  if (components != 1 && components != 3) {
    jpeg_destroy_decompress(&state->info);
    return Error{"JPEG with " + std::to_string(components) + " components (grey and colour are read)"};
  }
  const bool grey = read == ImageRead::kGrey || (read == ImageRead::kAsStored && components == 1);
  state->info.out_color_space = grey ? JCS_GRAYSCALE : JCS_EXT_BGR;
  jpeg_start_decompress(&state->info);
  state->image.create(static_cast<int>(state->info.output_height), static_cast<int>(state->info.output_width),
                      grey ? CV_8UC1 : CV_8UC3);
  while (state->info.output_scanline < state->info.output_height) {
    JSAMPROW row = state->image.ptr<uint8_t>(static_cast<int>(state->info.output_scanline));
    jpeg_read_scanlines(&state->info, &row, 1);
  }
  jpeg_finish_decompress(&state->info);
  jpeg_destroy_decompress(&state->info);
  if (state->errors.corrupt > 0) return Error{std::string("corrupt or truncated JPEG (") + state->errors.message + ")"};
  return state->image;
}

// ---- PNG ----

struct PngState {
  png_structp png = nullptr;
  png_infop info = nullptr;
  std::string message;
  const uint8_t* data = nullptr;  // reading: the stream and how far it is read
  size_t size = 0, at = 0;
  std::vector<uint8_t> out;  // writing
  cv::Mat image;
  std::vector<png_bytep> rows;
};

void pngFail(png_structp png, png_const_charp message) {
  static_cast<PngState*>(png_get_error_ptr(png))->message = message;
  png_longjmp(png, 1);
}

void pngWarn(png_structp, png_const_charp) {}  // ancillary trouble only: the pixels stand

void pngRead(png_structp png, png_bytep out, size_t bytes) {
  auto* state = static_cast<PngState*>(png_get_io_ptr(png));
  if (bytes > state->size - state->at) png_error(png, "truncated PNG");
  std::memcpy(out, state->data + state->at, bytes);
  state->at += bytes;
}

void pngWrite(png_structp png, png_bytep in, size_t bytes) {
  auto* state = static_cast<PngState*>(png_get_io_ptr(png));
  state->out.insert(state->out.end(), in, in + bytes);
}

void pngFlush(png_structp) {}

// The transforms that give 'read' from what the stream holds: grey as 8-bit grey, colour as
// 8-bit BGR, as stored with its own depth and channels (colour as BGR, palette expanded).
// Returns the image's type.
int pngTransforms(png_structp png, png_infop info, ImageRead read) {
  const int bit_depth = png_get_bit_depth(png, info);
  const int colour_type = png_get_color_type(png, info);
  if (colour_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (colour_type == PNG_COLOR_TYPE_GRAY && bit_depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  const bool has_colour = (colour_type & PNG_COLOR_MASK_COLOR) != 0;
  bool alpha = (colour_type & PNG_COLOR_MASK_ALPHA) != 0;
  if (png_get_valid(png, info, PNG_INFO_tRNS)) {
    if (read == ImageRead::kAsStored) {
      png_set_tRNS_to_alpha(png);
      alpha = true;
    } else {
      png_set_strip_alpha(png);
    }
  }
  int depth = bit_depth == 16 ? CV_16U : CV_8U;
  if (read != ImageRead::kAsStored) {
    if (bit_depth == 16) png_set_strip_16(png);
    depth = CV_8U;
    if (alpha) png_set_strip_alpha(png);
    alpha = false;
  }
  int channels = 1;
  if (read == ImageRead::kGrey) {
    if (has_colour) png_set_rgb_to_gray_fixed(png, 1, 29900, 58700);  // Rec. 601 luma, as OpenCV
  } else if (read == ImageRead::kColour || has_colour || alpha) {
    if (!has_colour) png_set_gray_to_rgb(png);
    png_set_bgr(png);
    channels = alpha ? 4 : 3;
  }
  if (depth == CV_16U) png_set_swap(png);  // PNG is big-endian; cv::Mat holds this host's order
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  return CV_MAKETYPE(depth, channels);
}

Expected<cv::Mat> decodePng(const uint8_t* data, size_t size, ImageRead read) {
  auto state = std::make_unique<PngState>();
  state->data = data, state->size = size;
  state->png = png_create_read_struct(PNG_LIBPNG_VER_STRING, state.get(), pngFail, pngWarn);
  if (!state->png) return Error{"PNG decoder not made (out of memory)"};
  state->info = png_create_info_struct(state->png);
  if (!state->info) {
    png_destroy_read_struct(&state->png, nullptr, nullptr);
    return Error{"PNG decoder not made (out of memory)"};
  }
  if (setjmp(png_jmpbuf(state->png))) {
    png_destroy_read_struct(&state->png, &state->info, nullptr);
    return Error{"corrupt PNG (" + state->message + ")"};
  }
  png_set_user_limits(state->png, kMaxDecodedSide, kMaxDecodedSide);
  png_set_read_fn(state->png, state.get(), pngRead);
  png_read_info(state->png, state->info);
  const int type = pngTransforms(state->png, state->info, read);
  const int width = static_cast<int>(png_get_image_width(state->png, state->info));
  const int height = static_cast<int>(png_get_image_height(state->png, state->info));
  if (png_get_rowbytes(state->png, state->info) != static_cast<size_t>(width) * CV_ELEM_SIZE(type)) {
    png_error(state->png, "unexpected row size after its transforms");
  }
  state->image.create(height, width, type);
  state->rows.resize(static_cast<size_t>(height));
  for (int v = 0; v < height; ++v) state->rows[static_cast<size_t>(v)] = state->image.ptr<uint8_t>(v);
  png_read_image(state->png, state->rows.data());
  png_read_end(state->png, nullptr);
  png_destroy_read_struct(&state->png, &state->info, nullptr);
  return state->image;
}

}  // namespace

std::vector<uint8_t> encodeJpeg(const cv::Mat& image, int quality, bool optimal_huffman) {
  CV_Assert(image.depth() == CV_8U && (image.channels() == 1 || image.channels() == 3) && !image.empty());
  auto state = std::make_unique<JpegEncoding>();
  state->info.err = &useErrors(&state->errors)->manager;
  jpeg_create_compress(&state->info);
  if (setjmp(state->errors.jump)) {  // only a programming error or no memory gets here
    jpeg_destroy_compress(&state->info);
    std::free(state->bytes);
    CV_Error(cv::Error::StsError, std::string("JPEG encoding failed: ") + state->errors.message);
  }
  jpeg_mem_dest(&state->info, &state->bytes, &state->size);
  state->info.image_width = static_cast<JDIMENSION>(image.cols);
  state->info.image_height = static_cast<JDIMENSION>(image.rows);
  state->info.input_components = image.channels();
  state->info.in_color_space = image.channels() == 1 ? JCS_GRAYSCALE : JCS_EXT_BGR;
  jpeg_set_defaults(&state->info);
  jpeg_set_quality(&state->info, std::clamp(quality, 1, 100), TRUE);  // baseline tables
  state->info.optimize_coding = optimal_huffman ? TRUE : FALSE;
  jpeg_start_compress(&state->info, TRUE);
  while (state->info.next_scanline < state->info.image_height) {
    JSAMPROW row = const_cast<uint8_t*>(image.ptr<uint8_t>(static_cast<int>(state->info.next_scanline)));
    jpeg_write_scanlines(&state->info, &row, 1);
  }
  jpeg_finish_compress(&state->info);
  jpeg_destroy_compress(&state->info);
  std::vector<uint8_t> out(state->bytes, state->bytes + state->size);
  std::free(state->bytes);
  return out;
}

std::vector<uint8_t> encodePng(const cv::Mat& image) {
  CV_Assert((image.depth() == CV_8U || image.depth() == CV_16U) && !image.empty() &&
            (image.channels() == 1 || image.channels() == 3 || image.channels() == 4));
  auto state = std::make_unique<PngState>();
  state->png = png_create_write_struct(PNG_LIBPNG_VER_STRING, state.get(), pngFail, pngWarn);
  if (state->png) state->info = png_create_info_struct(state->png);
  if (!state->png || !state->info) {
    png_destroy_write_struct(&state->png, nullptr);
    CV_Error(cv::Error::StsNoMem, "PNG encoder not made");
  }
  if (setjmp(png_jmpbuf(state->png))) {  // only a programming error or no memory gets here
    png_destroy_write_struct(&state->png, &state->info);
    CV_Error(cv::Error::StsError, "PNG encoding failed: " + state->message);
  }
  png_set_write_fn(state->png, state.get(), pngWrite, pngFlush);
  png_set_compression_level(state->png, 1);  // fast: these images go to files and the link
  const int colour_type = image.channels() == 1 ? PNG_COLOR_TYPE_GRAY
                          : image.channels() == 3 ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_RGB_ALPHA;
  png_set_IHDR(state->png, state->info, static_cast<png_uint_32>(image.cols), static_cast<png_uint_32>(image.rows),
               image.depth() == CV_16U ? 16 : 8, colour_type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_BASE,
               PNG_FILTER_TYPE_BASE);
  png_write_info(state->png, state->info);
  if (image.channels() > 1) png_set_bgr(state->png);
  if (image.depth() == CV_16U) png_set_swap(state->png);
  for (int v = 0; v < image.rows; ++v) png_write_row(state->png, const_cast<uint8_t*>(image.ptr<uint8_t>(v)));
  png_write_end(state->png, state->info);
  png_destroy_write_struct(&state->png, &state->info);
  return std::move(state->out);
}

Status writePngFile(const std::string& path, const cv::Mat& image) {
  std::vector<uint8_t> bytes;
  try {
    bytes = encodePng(image);
  } catch (const cv::Exception& e) {
    return Error{path + ": cannot encode image (" + e.msg + ")"};
  }
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out || !out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size())) ||
      !out.flush()) {
    return Error{path + ": cannot write image"};
  }
  return Status{};
}

Expected<cv::Mat> decodeImage(const uint8_t* data, size_t size, ImageRead read, cv::Size expected) {
  if (size == 0) return Error{"empty compressed image"};
  // The header first: a few bytes may declare a gigapixel image, which the decoder would
  // allocate before anything else is checked.
  const Expected<cv::Size> declared = encodedImageSize(data, size);
  if (!declared) return Error{declared.error()};
  if (*declared != expected) {
    return Error{"image header says " + std::to_string(declared->width) + "x" + std::to_string(declared->height) +
                 ", expected " + std::to_string(expected.width) + "x" + std::to_string(expected.height)};
  }
  const bool jpeg = size >= 2 && data[0] == 0xFF && data[1] == 0xD8;  // else PNG: encodedImageSize read no other
  Expected<cv::Mat> image = jpeg ? decodeJpeg(data, size, read) : decodePng(data, size, read);
  if (!image) return Error{"image does not decode: " + image.error()};
  if (image->size() != expected) {
    return Error{"decoded image is " + std::to_string(image->cols) + "x" + std::to_string(image->rows) + ", expected " +
                 std::to_string(expected.width) + "x" + std::to_string(expected.height)};
  }
  return image;
}

Expected<cv::Mat> decodeImage(const uint8_t* data, size_t size, int channels, int width, int height) {
  return decodeImage(data, size, channels == 1 ? ImageRead::kGrey : ImageRead::kColour, cv::Size(width, height));
}

}  // namespace rgbdslam
