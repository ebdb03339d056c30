// codec.h's JPEG and PNG coding, through libjpeg-turbo and libpng directly.
//
// Why not OpenCV's imgcodecs: Debian builds it with every image format it knows (GDAL,
// GDCM, poppler, ...), and linking it put 160 libraries into rgbd-tracker (47 without): 37
// MiB of resident memory before the program does anything (a program that only links it,
// measured against one that does not; most of rgbd-tracker's 57 MiB of library pages). The
// suite uses two formats, and the onboard tracker's memory budget is 150 MB
// (docs/open_work.md, session 42). The settings are OpenCV's own (jpeg_set_defaults,
// baseline quality tables, optional optimised Huffman tables, islow DCT; PNG at zlib level
// 1), so a JPEG's bytes and every decoded pixel are as before (tests/image/test_codec.cpp
// compares them with imgcodecs).
//
// Both libraries report errors by longjmp to the call's setjmp, set before the first call
// that may fail. Everything written after the setjmp lives in a heap-allocated state (an
// automatic variable changed between setjmp and longjmp would be indeterminate), and no
// object with a destructor is left between the two: the jumps cross only the libraries' C
// frames, and the callbacks of ours they call let no exception out.
//
// Hostile input: the size is checked against the expected one before a pixel is allocated
// (the header walk of codec.cpp first, then libjpeg's and libpng's own reading of it, which
// a crafted stream can make differ), any libjpeg warning (corrupt data it would decode on
// past) ends the decoding at once, a JPEG of more than kMaxJpegScans scans (a progressive
// stream can hold thousands, each a pass over the image) is refused, libjpeg's working
// memory is held to what a progressive colour image of the expected size needs, and a PNG's
// ancillary chunks other than tRNS are skipped unread (compressed text could inflate to
// gigabytes).
#include <algorithm>
#include <csetjmp>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <new>
#include <string>

#include "rgbdslam/image/codec.h"

// After <cstdio> and <cstddef>: jpeglib.h uses FILE and size_t without including them.
#include <jpeglib.h>
#include <jerror.h>  // after jpeglib.h: ERREXIT and the message codes
#include <png.h>

namespace rgbdslam {
namespace {

// Runs 'allocate' (an image's buffer, within the expected size); false if there was no
// memory, so that the caller can destroy its decoder before it returns.
template <typename Allocate>
bool allocated(Allocate allocate) {
  try {
    allocate();
  } catch (const std::exception&) {  // cv::Exception or std::bad_alloc
    return false;
  }
  return true;
}

// ---- JPEG ----

constexpr int kMaxJpegScans = 32;  // a baseline JPEG has 1, libjpeg's progressive ones 6-10

struct JpegErrors {
  jpeg_error_mgr manager;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX] = "";
};

void jpegFail(j_common_ptr info) {
  auto* errors = reinterpret_cast<JpegErrors*>(info->err);
  (*info->err->format_message)(info, errors->message);
  std::longjmp(errors->jump, 1);
}

// libjpeg calls this with level -1 for a warning: corrupt or missing data it would decode on
// past, making up what is missing. Here that ends the decoding. Levels >= 0 are traces.
void jpegMessage(j_common_ptr info, int level) {
  if (level < 0) jpegFail(info);
}

// Between the passes over a progressive stream's scans.
void jpegProgress(j_common_ptr info) {
  if (info->is_decompressor && reinterpret_cast<j_decompress_ptr>(info)->input_scan_number > kMaxJpegScans) {
    std::snprintf(reinterpret_cast<JpegErrors*>(info->err)->message, JMSG_LENGTH_MAX, "more than %d scans",
                  kMaxJpegScans);
    std::longjmp(reinterpret_cast<JpegErrors*>(info->err)->jump, 1);
  }
}

jpeg_error_mgr* useErrors(JpegErrors* errors) {
  jpeg_std_error(&errors->manager);
  errors->manager.error_exit = jpegFail;
  errors->manager.emit_message = jpegMessage;
  return &errors->manager;
}

// The encoder's output grows in a vector the state owns (jpeg_mem_dest's buffer is freed and
// replaced as it grows, and a failure half way would leave the state holding a freed one).
struct JpegEncoding {
  jpeg_compress_struct info;
  JpegErrors errors;
  jpeg_destination_mgr destination;
  std::vector<uint8_t> out;
};

// One more block of output room, the bytes so far kept; false if there is no memory.
bool growJpegOutput(JpegEncoding* state, size_t used) {
  try {
    state->out.resize(std::max<size_t>(2 * state->out.size(), 1 << 16));
  } catch (...) {  // bad_alloc, length_error: nothing may cross the library's frames
    return false;
  }
  state->destination.next_output_byte = state->out.data() + used;
  state->destination.free_in_buffer = state->out.size() - used;
  return true;
}

JpegEncoding* encodingOf(j_compress_ptr info) { return static_cast<JpegEncoding*>(info->client_data); }

void jpegOutputStart(j_compress_ptr info) {
  if (!growJpegOutput(encodingOf(info), 0)) ERREXIT(info, JERR_OUT_OF_MEMORY);
}

boolean jpegOutputFull(j_compress_ptr info) {
  JpegEncoding* state = encodingOf(info);
  if (!growJpegOutput(state, state->out.size())) ERREXIT(info, JERR_OUT_OF_MEMORY);
  return TRUE;
}

void jpegOutputEnd(j_compress_ptr info) {
  JpegEncoding* state = encodingOf(info);
  state->out.resize(state->out.size() - state->destination.free_in_buffer);  // shrinks: no allocation
}

struct JpegDecoding {
  jpeg_decompress_struct info;
  JpegErrors errors;
  jpeg_progress_mgr progress;
  cv::Mat image;
};

Expected<cv::Mat> decodeJpeg(const uint8_t* data, size_t size, ImageRead read, cv::Size expected) {
  auto state = std::make_unique<JpegDecoding>();  // zeroed: destroying it before create is safe
  state->info.err = useErrors(&state->errors);
  if (setjmp(state->errors.jump)) {
    jpeg_destroy_decompress(&state->info);
    return Error{std::string("corrupt JPEG (") + state->errors.message + ")"};
  }
  jpeg_create_decompress(&state->info);
  state->progress.progress_monitor = jpegProgress;
  state->info.progress = &state->progress;
  // A progressive stream's coefficients (2 bytes each, 3 components at full resolution at
  // most), plus working memory: beyond it libjpeg stops with "backing store not supported".
  state->info.mem->max_memory_to_use =
      6L * expected.width * expected.height + (16L << 20);
  jpeg_mem_src(&state->info, data, static_cast<unsigned long>(size));
  jpeg_read_header(&state->info, TRUE);
  const int components = state->info.num_components;
  const bool declared = static_cast<int>(state->info.image_width) == expected.width &&
                        static_cast<int>(state->info.image_height) == expected.height;
  if (components != 1 && components != 3) {
    jpeg_destroy_decompress(&state->info);
    return Error{"JPEG with " + std::to_string(components) + " components (grey and colour are read)"};
  }
  if (!declared) {  // another frame header than the one codec.cpp's walk found
    jpeg_destroy_decompress(&state->info);
    return Error{"JPEG frame header says " + std::to_string(state->info.image_width) + "x" +
                 std::to_string(state->info.image_height) + ", expected " + std::to_string(expected.width) + "x" +
                 std::to_string(expected.height)};
  }
  const bool grey = read == ImageRead::kGrey || (read == ImageRead::kAsStored && components == 1);
  state->info.out_color_space = grey ? JCS_GRAYSCALE : JCS_EXT_BGR;
  jpeg_start_decompress(&state->info);
  if (static_cast<int>(state->info.output_width) != expected.width ||
      static_cast<int>(state->info.output_height) != expected.height ||
      state->info.output_components != (grey ? 1 : 3)) {
    jpeg_destroy_decompress(&state->info);
    return Error{"JPEG decodes to another size or number of channels than it declared"};
  }
  if (!allocated([&] { state->image.create(expected.height, expected.width, grey ? CV_8UC1 : CV_8UC3); })) {
    jpeg_destroy_decompress(&state->info);
    return Error{"no memory for the image"};
  }
  while (state->info.output_scanline < state->info.output_height) {
    JSAMPROW row = state->image.ptr<uint8_t>(static_cast<int>(state->info.output_scanline));
    jpeg_read_scanlines(&state->info, &row, 1);
  }
  jpeg_finish_decompress(&state->info);
  jpeg_destroy_decompress(&state->info);
  return state->image;
}

// ---- PNG ----

constexpr bool kLittleEndianHost = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;

struct PngState {
  png_structp png = nullptr;
  png_infop info = nullptr;
  char message[256] = "";
  const uint8_t* data = nullptr;  // reading: the stream and how far it is read
  size_t size = 0, at = 0;
  std::vector<uint8_t> out;  // writing
  cv::Mat image;
  std::vector<png_bytep> rows;
};

void pngFail(png_structp png, png_const_charp message) {
  auto* state = static_cast<PngState*>(png_get_error_ptr(png));
  std::snprintf(state->message, sizeof state->message, "%s", message);
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
  bool grown = true;
  try {
    state->out.insert(state->out.end(), in, in + bytes);
  } catch (...) {  // bad_alloc, length_error: nothing may cross the library's frames
    grown = false;
  }
  if (!grown) png_error(png, "out of memory");
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
  const bool has_colour = (colour_type & PNG_COLOR_MASK_COLOR) != 0;  // palette too
  bool alpha = (colour_type & PNG_COLOR_MASK_ALPHA) != 0;
  // A transparent colour (tRNS) is an alpha channel as stored for colour and palette images
  // (a palette's expansion makes one anyway); a grey image stays one channel, as OpenCV reads it.
  if (png_get_valid(png, info, PNG_INFO_tRNS) && has_colour) {
    png_set_tRNS_to_alpha(png);
    alpha = true;
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
  if (depth == CV_16U && kLittleEndianHost) png_set_swap(png);  // PNG is big-endian
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  return CV_MAKETYPE(depth, channels);
}

Expected<cv::Mat> decodePng(const uint8_t* data, size_t size, ImageRead read, cv::Size expected) {
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
    return Error{std::string("corrupt PNG (") + state->message + ")"};
  }
  png_set_user_limits(state->png, kMaxDecodedSide, kMaxDecodedSide);
  png_set_keep_unknown_chunks(state->png, PNG_HANDLE_CHUNK_NEVER, nullptr, -1);  // all but the critical ones and tRNS
  png_set_chunk_malloc_max(state->png, 1 << 20);  // [bytes] what a chunk read whole may take
  png_set_read_fn(state->png, state.get(), pngRead);
  png_read_info(state->png, state->info);
  const int type = pngTransforms(state->png, state->info, read);
  const int width = static_cast<int>(png_get_image_width(state->png, state->info));
  const int height = static_cast<int>(png_get_image_height(state->png, state->info));
  if (width != expected.width || height != expected.height) png_error(state->png, "IHDR differs from the size read");
  if (png_get_rowbytes(state->png, state->info) != static_cast<size_t>(width) * CV_ELEM_SIZE(type)) {
    png_error(state->png, "unexpected row size after its transforms");
  }
  if (!allocated([&] {
        state->image.create(height, width, type);
        state->rows.resize(static_cast<size_t>(height));
      })) {
    png_destroy_read_struct(&state->png, &state->info, nullptr);
    return Error{"no memory for the image"};
  }
  for (int v = 0; v < height; ++v) state->rows[static_cast<size_t>(v)] = state->image.ptr<uint8_t>(v);
  png_read_image(state->png, state->rows.data());
  png_read_end(state->png, nullptr);
  png_destroy_read_struct(&state->png, &state->info, nullptr);
  return state->image;
}

}  // namespace

std::vector<uint8_t> encodeJpeg(const cv::Mat& image, int quality, bool optimal_huffman) {
  CV_Assert(image.depth() == CV_8U && (image.channels() == 1 || image.channels() == 3) && !image.empty());
  auto state = std::make_unique<JpegEncoding>();  // zeroed: destroying it before create is safe
  state->info.err = useErrors(&state->errors);
  if (setjmp(state->errors.jump)) {  // only a programming error or no memory gets here
    jpeg_destroy_compress(&state->info);
    CV_Error(cv::Error::StsError, std::string("JPEG encoding failed: ") + state->errors.message);
  }
  jpeg_create_compress(&state->info);
  state->info.client_data = state.get();
  state->destination.init_destination = jpegOutputStart;
  state->destination.empty_output_buffer = jpegOutputFull;
  state->destination.term_destination = jpegOutputEnd;
  state->info.dest = &state->destination;
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
  return std::move(state->out);
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
    CV_Error(cv::Error::StsError, std::string("PNG encoding failed: ") + state->message);
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
  if (image.depth() == CV_16U && kLittleEndianHost) png_set_swap(state->png);
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
  // Each decoder checks its library's own reading of the size against 'expected' before it
  // allocates, and returns an image of that size or an error.
  const bool jpeg = size >= 2 && data[0] == 0xFF && data[1] == 0xD8;  // else PNG: encodedImageSize read no other
  Expected<cv::Mat> image = jpeg ? decodeJpeg(data, size, read, expected) : decodePng(data, size, read, expected);
  if (!image) return Error{"image does not decode: " + image.error()};
  return image;
}

Expected<cv::Mat> decodeImage(const uint8_t* data, size_t size, int channels, int width, int height) {
  return decodeImage(data, size, channels == 1 ? ImageRead::kGrey : ImageRead::kColour, cv::Size(width, height));
}

}  // namespace rgbdslam
