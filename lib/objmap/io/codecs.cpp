#include "objmap/io/codecs.h"

#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include <jpeglib.h>  // after <cstdio>: it uses FILE
#include <png.h>

namespace objmap::io {

namespace {

// Both libraries report an error by a longjmp out of the library call. Each call of a library that
// may fail runs as a step of the decoding (a function of one argument, the decoding's state) in
// the functions below, which set the jump target and say whether the step got through. A step has
// no local object with a destructor (a longjmp would skip it); the state, and what frees the
// library's memory, live in the caller.
template <typename State>
bool step_ok(std::jmp_buf& target, void (*step)(State&), State& state) {
  if (setjmp(target) != 0) return false;
  step(state);
  return true;
}

// OpenCV's limit on the pixels of a decoded image (CV_IO_MAX_IMAGE_PIXELS): a header claiming more
// is refused before any buffer is made.
constexpr std::uint64_t kMaxPixels = std::uint64_t{1} << 30;

bool too_large(std::uint64_t width, std::uint64_t height, std::string& error) {
  if (width * height <= kMaxPixels) return false;
  error = "the header claims " + std::to_string(width) + "x" + std::to_string(height) +
          " pixels, more than " + std::to_string(kMaxPixels);
  return true;
}

bool little_endian_host() {
  const std::uint16_t one = 1;
  unsigned char first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

// ---- PNG (libpng) -------------------------------------------------------------------------------

struct PngRead {
  png_structp png = nullptr;
  png_infop info = nullptr;
  const unsigned char* data = nullptr;
  std::size_t size = 0, at = 0;  // the bytes and how many libpng has read
  char message[256] = "";        // libpng's error
  png_uint_32 width = 0, height = 0;
  int type = -1;              // the Mat type, set by png_header
  png_bytepp rows = nullptr;  // where png_pixels writes, row by row
  PngRead() = default;
  PngRead(const PngRead&) = delete;
  PngRead& operator=(const PngRead&) = delete;
  ~PngRead() { png_destroy_read_struct(&png, &info, nullptr); }  // null pointers are fine
};

void png_on_error(png_structp png, png_const_charp message) {
  auto* read = static_cast<PngRead*>(png_get_error_ptr(png));
  std::snprintf(read->message, sizeof read->message, "%s", message);
  png_longjmp(png, 1);  // (returning would print the message to stderr, then jump)
}

// Warnings (e.g. a damaged ancillary chunk, which libpng skips) do not stop the decoding, as in
// OpenCV; they are not printed.
void png_on_warning(png_structp, png_const_charp) {}

void png_read_memory(png_structp png, png_bytep out, png_size_t n) {
  auto* read = static_cast<PngRead*>(png_get_io_ptr(png));
  if (n > read->size - read->at) png_error(png, "the data ends early");
  std::memcpy(out, read->data + read->at, n);
  read->at += n;
}

// The header, the Mat type OpenCV's PngDecoder::readHeader chooses and the transformations its
// readData asks libpng for, for that type (IMREAD_UNCHANGED: the file's bit depth).
void png_header(PngRead& r) {
  png_read_info(r.png, r.info);
  int bit_depth = 0, colour = 0;
  png_get_IHDR(r.png, r.info, &r.width, &r.height, &bit_depth, &colour, nullptr, nullptr, nullptr);
  int num_trans = 0;
  if (colour == PNG_COLOR_TYPE_RGB || colour == PNG_COLOR_TYPE_PALETTE) {
    png_bytep trans = nullptr;
    png_color_16p trans_colour = nullptr;
    png_get_tRNS(r.png, r.info, &trans, &num_trans, &trans_colour);
  }
  int channels = 1;  // grey, with or without tRNS
  if (colour == PNG_COLOR_TYPE_RGB || colour == PNG_COLOR_TYPE_PALETTE)
    channels = num_trans > 0 ? 4 : 3;
  else if (colour == PNG_COLOR_TYPE_GRAY_ALPHA || colour == PNG_COLOR_TYPE_RGB_ALPHA)
    channels = 4;
  const bool wide = bit_depth == 16;
  if (wide && little_endian_host()) png_set_swap(r.png);
  if (channels < 4)
    png_set_strip_alpha(r.png);
  else
    png_set_tRNS_to_alpha(r.png);
  if (colour == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(r.png);
  if ((colour & PNG_COLOR_MASK_COLOR) == 0 && bit_depth < 8) png_set_expand_gray_1_2_4_to_8(r.png);
  if ((colour & PNG_COLOR_MASK_COLOR) != 0 && channels > 1)
    png_set_bgr(r.png);
  else if (channels > 1)
    png_set_gray_to_rgb(r.png);  // grey + alpha: B = G = R
  // (One channel is a grey file: OpenCV's png_set_rgb_to_gray then changes nothing.)
  png_set_interlace_handling(r.png);
  png_read_update_info(r.png, r.info);
  r.type = CV_MAKETYPE(wide ? CV_16U : CV_8U, channels);
  // libpng writes whole rows: they must be the Mat's rows exactly.
  if (png_get_rowbytes(r.png, r.info) !=
      static_cast<std::size_t>(r.width) * channels * (wide ? 2 : 1))
    png_error(r.png, "unexpected row size after the transformations");
}

void png_pixels(PngRead& r) {
  png_read_image(r.png, r.rows);
  png_read_end(r.png, r.info);  // the chunks after the image data, CRCs checked
}

// ---- JPEG (libjpeg)
// ------------------------------------------------------------------------------

struct JpegErrors {
  jpeg_error_mgr manager;  // first: libjpeg hands &manager to jpeg_on_error
  std::jmp_buf jump;
};

void jpeg_on_error(j_common_ptr info) {
  std::longjmp(reinterpret_cast<JpegErrors*>(info->err)->jump, 1);
}

// Warnings (e.g. corrupt entropy-coded data, which libjpeg gets over) do not stop the decoding, as
// in OpenCV; they are not printed.
void jpeg_on_message(j_common_ptr, int) {}

struct JpegRead {
  jpeg_decompress_struct info{};  // zeroed: destroying it before it is created does nothing
  JpegErrors errors{};
  const unsigned char* data = nullptr;
  std::size_t size = 0;
  unsigned char* pixels = nullptr;  // the Mat's first row and its step, for jpeg_pixels
  std::size_t step = 0;
  bool short_read = false;  // libjpeg gave fewer rows than the header says
  JpegRead() {
    info.err = jpeg_std_error(&errors.manager);
    errors.manager.error_exit = jpeg_on_error;
    errors.manager.emit_message = jpeg_on_message;
  }
  JpegRead(const JpegRead&) = delete;
  JpegRead& operator=(const JpegRead&) = delete;
  ~JpegRead() { jpeg_destroy_decompress(&info); }
  std::string message() {
    char text[JMSG_LENGTH_MAX] = "";
    errors.manager.format_message(reinterpret_cast<j_common_ptr>(&info), text);
    return text;
  }
};

void jpeg_header(JpegRead& r) {
  jpeg_create_decompress(&r.info);
  jpeg_mem_src(&r.info, r.data, static_cast<unsigned long>(r.size));
  jpeg_read_header(&r.info, TRUE);
}

// As OpenCV's JpegDecoder::readData: grey stays grey, colour comes as RGB (swapped to BGR below).
void jpeg_start(JpegRead& r) {
  r.info.out_color_space = r.info.num_components == 1 ? JCS_GRAYSCALE : JCS_RGB;
  jpeg_start_decompress(&r.info);
}

void jpeg_pixels(JpegRead& r) {
  while (r.info.output_scanline < r.info.output_height) {
    JSAMPROW row = r.pixels + r.step * r.info.output_scanline;
    if (jpeg_read_scanlines(&r.info, &row, 1) != 1) {
      r.short_read = true;
      return;
    }
  }
  jpeg_finish_decompress(&r.info);
}

}  // namespace

cv::Mat decode_png(const unsigned char* data, std::size_t size, std::string& error) {
  PngRead r;
  r.data = data;
  r.size = size;
  r.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &r, png_on_error, png_on_warning);
  if (r.png != nullptr) r.info = png_create_info_struct(r.png);
  if (r.png == nullptr || r.info == nullptr) {
    error = "libpng: out of memory";
    return {};
  }
  png_set_read_fn(r.png, &r, png_read_memory);
  if (!step_ok(png_jmpbuf(r.png), png_header, r)) {
    error = std::string("libpng: ") + r.message;
    return {};
  }
  if (too_large(r.width, r.height, error)) return {};
  cv::Mat image(static_cast<int>(r.height), static_cast<int>(r.width), r.type);
  std::vector<png_bytep> rows(r.height);
  for (int y = 0; y < image.rows; ++y) rows[y] = image.ptr(y);
  r.rows = rows.data();
  if (!step_ok(png_jmpbuf(r.png), png_pixels, r)) {
    error = std::string("libpng: ") + r.message;
    return {};
  }
  return image;
}

bool jpeg_size(const unsigned char* data, std::size_t size, std::uint32_t& width,
               std::uint32_t& height) {
  JpegRead r;
  r.data = data;
  r.size = size;
  if (!step_ok(r.errors.jump, jpeg_header, r)) return false;
  width = r.info.image_width;
  height = r.info.image_height;
  return true;
}

cv::Mat decode_jpeg(const unsigned char* data, std::size_t size, std::string& error) {
  JpegRead r;
  r.data = data;
  r.size = size;
  if (!step_ok(r.errors.jump, jpeg_header, r)) {
    error = "libjpeg: " + r.message();
    return {};
  }
  const int components = r.info.num_components;
  if (components == 4) {
    error = std::string("unsupported ") + (r.info.jpeg_color_space == JCS_YCCK ? "YCCK" : "CMYK") +
            " JPEG (4 colour components): only grey and colour (YCbCr or RGB) JPEGs are read";
    return {};
  }
  if (components != 1 && components != 3) {
    error = "unsupported JPEG of " + std::to_string(components) +
            " components: only grey (1) and colour (3) JPEGs are read";
    return {};
  }
  if (too_large(r.info.image_width, r.info.image_height, error)) return {};
  if (!step_ok(r.errors.jump, jpeg_start, r)) {
    error = "libjpeg: " + r.message();
    return {};
  }
  if (r.info.output_components != components) {
    error = "libjpeg: " + std::to_string(r.info.output_components) + " output components for " +
            std::to_string(components);
    return {};
  }
  cv::Mat image(static_cast<int>(r.info.output_height), static_cast<int>(r.info.output_width),
                CV_MAKETYPE(CV_8U, components));
  r.pixels = image.ptr();
  r.step = image.step;
  if (!step_ok(r.errors.jump, jpeg_pixels, r)) {
    error = "libjpeg: " + r.message();
    return {};
  }
  if (r.short_read) {
    error = "libjpeg: the image data ends early";
    return {};
  }
  if (components == 3) {
    for (int y = 0; y < image.rows; ++y) {
      unsigned char* p = image.ptr(y);
      for (int x = 0; x < image.cols; ++x, p += 3) std::swap(p[0], p[2]);  // RGB -> BGR
    }
  }
  return image;
}

}  // namespace objmap::io
