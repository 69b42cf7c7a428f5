#include "objmap/io/codecs.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <jpeglib.h>  // after <cstdio>
#include <png.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "io/image_checks.h"
#include "objmap/core/error.h"
#include "objmap/io/image.h"
#include "support/test_support.h"

// The decoders of io/codecs.h against OpenCV 4.6's cv::imdecode(IMREAD_UNCHANGED), which the
// tests link: every kind of PNG (written here by libpng, since OpenCV writes few of them) and of
// JPEG gives the same Mat, type, size and every byte.
namespace objmap::io {
namespace {

namespace fs = std::filesystem;
using image_checks::picture;
using image_checks::same_pixels;
using Bytes = std::vector<unsigned char>;

cv::Mat png_decoded(const Bytes& png, std::string* error_out = nullptr) {
  std::string error;
  cv::Mat image = decode_png(png.data(), png.size(), error);
  if (error_out != nullptr) *error_out = error;
  return image;
}

cv::Mat jpeg_decoded(const Bytes& jpeg, std::string* error_out = nullptr) {
  std::string error;
  cv::Mat image = decode_jpeg(jpeg.data(), jpeg.size(), error);
  if (error_out != nullptr) *error_out = error;
  return image;
}

// ---- PNGs written by libpng ---------------------------------------------------------------------

struct PngKind {
  const char* name;
  int colour_type;  // PNG_COLOR_TYPE_*
  int bit_depth;    // 1, 2, 4, 8, 16
  bool trns;        // with a tRNS chunk
  int want_type;    // what OpenCV gives
};

// The kinds OpenCV tells apart. Grey + tRNS stays grey (OpenCV strips the transparency); a colour
// or palette image with tRNS gets an alpha channel.
const PngKind kKinds[] = {
    {"grey 1-bit", PNG_COLOR_TYPE_GRAY, 1, false, CV_8UC1},
    {"grey 2-bit", PNG_COLOR_TYPE_GRAY, 2, false, CV_8UC1},
    {"grey 4-bit", PNG_COLOR_TYPE_GRAY, 4, false, CV_8UC1},
    {"grey 8-bit", PNG_COLOR_TYPE_GRAY, 8, false, CV_8UC1},
    {"grey 16-bit", PNG_COLOR_TYPE_GRAY, 16, false, CV_16UC1},
    {"grey 2-bit tRNS", PNG_COLOR_TYPE_GRAY, 2, true, CV_8UC1},
    {"grey 8-bit tRNS", PNG_COLOR_TYPE_GRAY, 8, true, CV_8UC1},
    {"grey 16-bit tRNS", PNG_COLOR_TYPE_GRAY, 16, true, CV_16UC1},
    {"grey+alpha 8-bit", PNG_COLOR_TYPE_GRAY_ALPHA, 8, false, CV_8UC4},
    {"grey+alpha 16-bit", PNG_COLOR_TYPE_GRAY_ALPHA, 16, false, CV_16UC4},
    {"RGB 8-bit", PNG_COLOR_TYPE_RGB, 8, false, CV_8UC3},
    {"RGB 16-bit", PNG_COLOR_TYPE_RGB, 16, false, CV_16UC3},
    {"RGB 8-bit tRNS", PNG_COLOR_TYPE_RGB, 8, true, CV_8UC4},
    {"RGB 16-bit tRNS", PNG_COLOR_TYPE_RGB, 16, true, CV_16UC4},
    {"RGBA 8-bit", PNG_COLOR_TYPE_RGB_ALPHA, 8, false, CV_8UC4},
    {"RGBA 16-bit", PNG_COLOR_TYPE_RGB_ALPHA, 16, false, CV_16UC4},
    {"palette 1-bit", PNG_COLOR_TYPE_PALETTE, 1, false, CV_8UC3},
    {"palette 2-bit", PNG_COLOR_TYPE_PALETTE, 2, false, CV_8UC3},
    {"palette 4-bit", PNG_COLOR_TYPE_PALETTE, 4, false, CV_8UC3},
    {"palette 8-bit", PNG_COLOR_TYPE_PALETTE, 8, false, CV_8UC3},
    {"palette 4-bit tRNS", PNG_COLOR_TYPE_PALETTE, 4, true, CV_8UC4},
    {"palette 8-bit tRNS", PNG_COLOR_TYPE_PALETTE, 8, true, CV_8UC4},
};

int samples_per_pixel(int colour_type) {
  switch (colour_type) {
    case PNG_COLOR_TYPE_GRAY_ALPHA:
      return 2;
    case PNG_COLOR_TYPE_RGB:
      return 3;
    case PNG_COLOR_TYPE_RGB_ALPHA:
      return 4;
    default:
      return 1;  // grey, palette
  }
}

// What libpng writes: the header, palette and tRNS, and the rows in PNG order (packed samples,
// 16-bit big-endian).
struct PngContent {
  int width = 0, height = 0, colour_type = 0, bit_depth = 0;
  bool interlaced = false;
  std::vector<png_color> palette;
  std::vector<png_byte> trns_alpha;  // palette tRNS: alpha of the first entries
  bool trns = false;
  png_color_16 trns_colour{};  // grey / RGB tRNS: the transparent sample values
  std::vector<Bytes> rows;
};

void write_to_vector(png_structp png, png_bytep data, png_size_t n) {
  auto* out = static_cast<Bytes*>(png_get_io_ptr(png));
  out->insert(out->end(), data, data + n);
}

void flush_nothing(png_structp) {}

// The PNG bytes of `content` (libpng's default filters and compression).
Bytes png_written(const PngContent& content) {
  Bytes out;
  std::vector<png_bytep> rows;
  for (const Bytes& row : content.rows) rows.push_back(const_cast<png_bytep>(row.data()));
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  if (setjmp(png_jmpbuf(png)) != 0) {
    png_destroy_write_struct(&png, &info);
    ADD_FAILURE() << "libpng could not write the test image";
    return {};
  }
  png_set_write_fn(png, &out, write_to_vector, flush_nothing);
  png_set_IHDR(png, info, content.width, content.height, content.bit_depth, content.colour_type,
               content.interlaced ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (!content.palette.empty())
    png_set_PLTE(png, info, content.palette.data(), static_cast<int>(content.palette.size()));
  if (content.trns) {
    png_set_tRNS(png, info, content.trns_alpha.empty() ? nullptr : content.trns_alpha.data(),
                 static_cast<int>(content.trns_alpha.size()), &content.trns_colour);
  }
  png_write_info(png, info);
  png_write_image(png, rows.data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return out;
}

// Random samples of `kind` (every palette index in range), the tRNS colour that of the first pixel
// and of every 7th pixel of each row, so that some pixels are transparent.
PngContent random_content(const PngKind& kind, int width, int height, bool interlaced,
                          std::uint64_t seed) {
  PngContent c;
  c.width = width;
  c.height = height;
  c.colour_type = kind.colour_type;
  c.bit_depth = kind.bit_depth;
  c.interlaced = interlaced;
  cv::RNG rng(seed);
  const int spp = samples_per_pixel(kind.colour_type);
  const std::size_t row_bytes = (static_cast<std::size_t>(width) * spp * kind.bit_depth + 7) / 8;
  for (int y = 0; y < height; ++y) {
    Bytes row(row_bytes);
    for (unsigned char& b : row) b = static_cast<unsigned char>(rng.uniform(0, 256));
    c.rows.push_back(row);
  }
  if (kind.colour_type == PNG_COLOR_TYPE_PALETTE) {
    c.palette.resize(std::size_t{1} << kind.bit_depth);
    for (png_color& p : c.palette) {
      p.red = static_cast<png_byte>(rng.uniform(0, 256));
      p.green = static_cast<png_byte>(rng.uniform(0, 256));
      p.blue = static_cast<png_byte>(rng.uniform(0, 256));
    }
  }
  if (!kind.trns) return c;
  c.trns = true;
  if (kind.colour_type == PNG_COLOR_TYPE_PALETTE) {
    c.trns_alpha = {0, 128, 255, 1, 77};  // the first five entries; the others opaque
    return c;
  }
  const int bytes_per_pixel = spp * kind.bit_depth / 8;  // 0 for packed grey
  if (bytes_per_pixel > 0) {
    for (Bytes& row : c.rows)
      for (int x = 7; x < width; x += 7)
        std::copy(c.rows[0].begin(), c.rows[0].begin() + bytes_per_pixel,
                  row.begin() + static_cast<std::size_t>(x) * bytes_per_pixel);
  }
  const Bytes& first = c.rows[0];
  auto sample = [&](int i) -> png_uint_16 {  // sample i of the first pixel
    if (kind.bit_depth == 16) return static_cast<png_uint_16>(first[2 * i] << 8 | first[2 * i + 1]);
    return static_cast<png_uint_16>(first[0] >> (8 - kind.bit_depth));  // (8-bit: the byte)
  };
  if (kind.colour_type == PNG_COLOR_TYPE_GRAY) {
    c.trns_colour.gray = sample(0);
  } else if (kind.bit_depth == 16) {
    c.trns_colour.red = sample(0);
    c.trns_colour.green = sample(1);
    c.trns_colour.blue = sample(2);
  } else {
    c.trns_colour.red = first[0];
    c.trns_colour.green = first[1];
    c.trns_colour.blue = first[2];
  }
  return c;
}

TEST(DecodePng, EveryKindAsOpenCvDecodesIt) {
  for (const PngKind& kind : kKinds) {
    for (bool interlaced : {false, true}) {
      // Odd sizes: partly filled bytes at the ends of packed rows, partly filled Adam7 passes.
      const Bytes png = png_written(random_content(kind, 37, 23, interlaced, 11));
      ASSERT_FALSE(png.empty()) << kind.name;
      ASSERT_EQ(png[8 + 8 + 12], interlaced ? 1 : 0) << "the IHDR's interlace method";
      const std::string what = std::string(kind.name) + (interlaced ? ", interlaced" : "");
      const cv::Mat want = cv::imdecode(png, cv::IMREAD_UNCHANGED);
      ASSERT_EQ(want.type(), kind.want_type) << what << ": OpenCV's type is not the one expected";
      std::string error;
      const cv::Mat got = png_decoded(png, &error);
      EXPECT_EQ(error, "") << what;
      EXPECT_TRUE(same_pixels(got, want)) << what;
    }
  }
}

TEST(DecodePng, TransparencyPaletteAndGreyAlphaAreWhatOpenCvMakesOfThem) {
  // The expectations of codecs.h, read off the decoded pixels: the tRNS colour is alpha 0, a
  // palette entry's tRNS alpha is its alpha, grey + alpha is B = G = R = grey.
  const PngKind rgb_trns{"RGB 8-bit tRNS", PNG_COLOR_TYPE_RGB, 8, true, CV_8UC4};
  const PngContent rgb = random_content(rgb_trns, 30, 5, false, 3);
  const cv::Mat bgra = png_decoded(png_written(rgb));
  ASSERT_EQ(bgra.type(), CV_8UC4);
  const Bytes& first = rgb.rows[0];
  EXPECT_EQ(bgra.at<cv::Vec4b>(0, 0), cv::Vec4b(first[2], first[1], first[0], 0));
  EXPECT_EQ(bgra.at<cv::Vec4b>(4, 7)[3], 0);  // every 7th pixel has the tRNS colour
  EXPECT_EQ(bgra.at<cv::Vec4b>(4, 8)[3], 255);

  const PngKind palette_trns{"palette 8-bit tRNS", PNG_COLOR_TYPE_PALETTE, 8, true, CV_8UC4};
  const PngContent palette = random_content(palette_trns, 30, 5, false, 4);
  const cv::Mat indexed = png_decoded(png_written(palette));
  ASSERT_EQ(indexed.type(), CV_8UC4);
  for (int x = 0; x < 30; ++x) {
    const int index = palette.rows[2][x];
    const png_color& p = palette.palette[index];
    const int alpha = index < 5 ? palette.trns_alpha[index] : 255;
    EXPECT_EQ(indexed.at<cv::Vec4b>(2, x), cv::Vec4b(p.blue, p.green, p.red, alpha)) << x;
  }

  const PngKind grey_alpha{"grey+alpha 8-bit", PNG_COLOR_TYPE_GRAY_ALPHA, 8, false, CV_8UC4};
  const PngContent ga = random_content(grey_alpha, 30, 5, false, 5);
  const cv::Mat gga = png_decoded(png_written(ga));
  ASSERT_EQ(gga.type(), CV_8UC4);
  const unsigned char g = ga.rows[1][2 * 3], a = ga.rows[1][2 * 3 + 1];
  EXPECT_EQ(gga.at<cv::Vec4b>(1, 3), cv::Vec4b(g, g, g, a));
}

TEST(DecodePng, OpenCvEncodedImagesAsOpenCvDecodesThem) {
  for (int type : {CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1, CV_16UC3, CV_16UC4}) {
    const cv::Mat image = picture(29, 41, type, 7u + type);
    Bytes png;
    ASSERT_TRUE(cv::imencode(".png", image, png));
    EXPECT_TRUE(same_pixels(png_decoded(png), cv::imdecode(png, cv::IMREAD_UNCHANGED))) << type;
    EXPECT_TRUE(same_pixels(png_decoded(png), image)) << type;
  }
}

TEST(DecodePng, ADamagedAncillaryChunkIsSkippedAsOpenCvSkipsIt) {
  PngKind kind{"palette 4-bit", PNG_COLOR_TYPE_PALETTE, 4, false, CV_8UC3};
  const Bytes png = png_written(random_content(kind, 9, 9, false, 6));
  // A tEXt chunk with a wrong CRC before IEND: libpng warns and skips it.
  Bytes text(png.begin(), png.end() - 12);
  const unsigned char chunk[] = {0, 0, 0, 3, 't', 'E', 'X', 't', 'a', 0, 'b', 1, 2, 3, 4};
  text.insert(text.end(), std::begin(chunk), std::end(chunk));
  text.insert(text.end(), png.end() - 12, png.end());
  const cv::Mat want = cv::imdecode(text, cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(want.empty());
  ::testing::internal::CaptureStderr();
  std::string error;
  const cv::Mat got = png_decoded(text, &error);
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");  // nothing printed
  EXPECT_EQ(error, "");
  EXPECT_TRUE(same_pixels(got, want));
}

TEST(DecodePng, DamageIsAnErrorNotAnImage) {
  PngKind kind{"palette 8-bit", PNG_COLOR_TYPE_PALETTE, 8, false, CV_8UC3};
  const Bytes png = png_written(random_content(kind, 40, 30, false, 8));
  const std::size_t idat = std::string(png.begin(), png.end()).find("IDAT");
  ASSERT_NE(idat, std::string::npos);
  // A flipped bit in the image data: zlib finds it first (libpng checks the chunk's CRC after
  // inflating its data).
  Bytes flipped = png;
  flipped[idat + 10] ^= 0x10;
  std::string error;
  EXPECT_TRUE(png_decoded(flipped, &error).empty());
  EXPECT_EQ(error.substr(0, 14), "libpng: IDAT: ") << error;
  EXPECT_TRUE(cv::imdecode(flipped, cv::IMREAD_UNCHANGED).empty());  // OpenCV fails too
  // A flipped bit in the CRC of the (last) IDAT chunk, the 4 bytes before IEND's 12.
  Bytes crc = png;
  crc[png.size() - 13] ^= 0x01;
  EXPECT_TRUE(png_decoded(crc, &error).empty());
  EXPECT_EQ(error, "libpng: IDAT: CRC error");
  EXPECT_TRUE(cv::imdecode(crc, cv::IMREAD_UNCHANGED).empty());

  // Cut short inside the image data (the end is gone, so the data ends early), and not a PNG.
  EXPECT_TRUE(png_decoded(Bytes(png.begin(), png.begin() + idat + 20), &error).empty());
  EXPECT_EQ(error, "libpng: the data ends early");
  EXPECT_TRUE(png_decoded({'n', 'o', 't', ' ', 'a', ' ', 'P', 'N', 'G'}, &error).empty());
  EXPECT_EQ(error, "libpng: Not a PNG file");
}

// ---- JPEG
// -----------------------------------------------------------------------------------------

// JPEG bytes written by libjpeg from `samples` (3 or 4 interleaved channels in the order of
// `in_space`, or 1), stored in `stored_space` with the first component's sampling factors h x v.
Bytes jpeg_written(const cv::Mat& samples, J_COLOR_SPACE in_space, J_COLOR_SPACE stored_space,
                   int h, int v) {
  jpeg_compress_struct info{};
  jpeg_error_mgr errors{};
  info.err = jpeg_std_error(&errors);  // (exits on an error: these inputs are valid)
  jpeg_create_compress(&info);
  unsigned char* buffer = nullptr;
  unsigned long size = 0;
  jpeg_mem_dest(&info, &buffer, &size);
  info.image_width = static_cast<JDIMENSION>(samples.cols);
  info.image_height = static_cast<JDIMENSION>(samples.rows);
  info.input_components = samples.channels();
  info.in_color_space = in_space;
  jpeg_set_defaults(&info);
  jpeg_set_colorspace(&info, stored_space);
  jpeg_set_quality(&info, 85, TRUE);
  info.comp_info[0].h_samp_factor = h;
  info.comp_info[0].v_samp_factor = v;
  jpeg_start_compress(&info, TRUE);
  while (info.next_scanline < info.image_height) {
    JSAMPROW row = const_cast<JSAMPROW>(samples.ptr(static_cast<int>(info.next_scanline)));
    jpeg_write_scanlines(&info, &row, 1);
  }
  jpeg_finish_compress(&info);
  jpeg_destroy_compress(&info);
  Bytes out(buffer, buffer + size);
  std::free(buffer);
  return out;
}

TEST(DecodeJpeg, ColourAndGreyAsOpenCvDecodesThem) {
  const cv::Mat colour = picture(45, 61, CV_8UC3, 21);  // odd sizes: partial blocks at the edges
  const cv::Mat grey = picture(45, 61, CV_8UC1, 22);
  const std::vector<std::pair<const char*, std::vector<int>>> settings{
      {"default (4:2:0, quality 95)", {}},
      {"quality 40", {cv::IMWRITE_JPEG_QUALITY, 40}},
      {"progressive", {cv::IMWRITE_JPEG_PROGRESSIVE, 1}},
      {"optimised Huffman tables", {cv::IMWRITE_JPEG_OPTIMIZE, 1}},
      {"restart markers", {cv::IMWRITE_JPEG_RST_INTERVAL, 2}},
      {"4:4:4 (luma and chroma qualities)",
       {cv::IMWRITE_JPEG_LUMA_QUALITY, 90, cv::IMWRITE_JPEG_CHROMA_QUALITY, 60}},
  };
  for (const auto& [name, params] : settings) {
    for (const cv::Mat& image : {colour, grey}) {
      Bytes jpeg;
      ASSERT_TRUE(cv::imencode(".jpg", image, jpeg, params));
      const cv::Mat want = cv::imdecode(jpeg, cv::IMREAD_UNCHANGED);
      ASSERT_EQ(want.type(), image.type()) << name;
      std::string error;
      const cv::Mat got = jpeg_decoded(jpeg, &error);
      EXPECT_EQ(error, "") << name;
      EXPECT_TRUE(same_pixels(got, want)) << name << ", " << image.channels() << " channel(s)";
    }
  }
}

TEST(DecodeJpeg, OtherSamplingsAndRgbJpegsAsOpenCvDecodesThem) {
  cv::Mat rgb = picture(33, 50, CV_8UC3, 23);  // taken as RGB by libjpeg
  for (const auto& [name, stored, h, v] :
       std::vector<std::tuple<const char*, J_COLOR_SPACE, int, int>>{
           {"4:2:2", JCS_YCbCr, 2, 1},
           {"4:4:0", JCS_YCbCr, 1, 2},
           {"4:1:1", JCS_YCbCr, 4, 1},
           {"RGB stored as RGB", JCS_RGB, 1, 1}}) {
    const Bytes jpeg = jpeg_written(rgb, JCS_RGB, stored, h, v);
    const cv::Mat want = cv::imdecode(jpeg, cv::IMREAD_UNCHANGED);
    ASSERT_EQ(want.type(), CV_8UC3) << name;
    EXPECT_TRUE(same_pixels(jpeg_decoded(jpeg), want)) << name;
  }
}

TEST(DecodeJpeg, CmykIsRefusedInOneLine) {
  const cv::Mat cmyk = picture(16, 16, CV_8UC4, 24);
  const Bytes jpeg = jpeg_written(cmyk, JCS_CMYK, JCS_CMYK, 1, 1);
  EXPECT_FALSE(cv::imdecode(jpeg, cv::IMREAD_UNCHANGED).empty());  // OpenCV converts it
  std::string error;
  EXPECT_TRUE(jpeg_decoded(jpeg, &error).empty());
  EXPECT_EQ(error,
            "unsupported CMYK JPEG (4 colour components): only grey and colour (YCbCr or RGB) "
            "JPEGs are read");
  const Bytes ycck = jpeg_written(cmyk, JCS_CMYK, JCS_YCCK, 1, 1);
  EXPECT_TRUE(jpeg_decoded(ycck, &error).empty());
  EXPECT_EQ(error.substr(0, 30), "unsupported YCCK JPEG (4 colou");
}

// A JPEG whose quantisation table segment (DQT) claims a length past the end of the file's
// headers: libjpeg stops with "Bogus marker length"-like errors; OpenCV gives an empty Mat.
Bytes corrupt_jpeg() {
  Bytes jpeg;
  EXPECT_TRUE(cv::imencode(".jpg", picture(20, 20, CV_8UC3, 25), jpeg));
  for (std::size_t i = 2; i + 3 < jpeg.size(); ++i) {
    if (jpeg[i] == 0xFF && jpeg[i + 1] == 0xDB) {  // DQT: its table precision/id byte
      jpeg[i + 4] = 0x37;                          // table 7 of precision 3: no such thing
      return jpeg;
    }
  }
  ADD_FAILURE() << "no DQT segment";
  return jpeg;
}

TEST(DecodeJpeg, DamageIsAnErrorNotAnImage) {
  const Bytes jpeg = corrupt_jpeg();
  EXPECT_TRUE(cv::imdecode(jpeg, cv::IMREAD_UNCHANGED).empty());
  std::string error;
  EXPECT_TRUE(jpeg_decoded(jpeg, &error).empty());
  EXPECT_EQ(error, "libjpeg: Bogus DQT index 7");
  EXPECT_TRUE(jpeg_decoded({0xFF, 0xD8, 0xFF, 0xD9}, &error).empty());
  EXPECT_EQ(error.substr(0, 9), "libjpeg: ");
  EXPECT_TRUE(jpeg_decoded({'n', 'o'}, &error).empty());
  EXPECT_EQ(error, "libjpeg: Not a JPEG file: starts with 0x6e 0x6f");
}

// ---- the real data
// -------------------------------------------------------------------------------

TEST(DecodeReal, EveryImageOfTheRealRecordingsAsOpenCvDecodesIt) {
  OBJMAP_DATA_OR_SKIP(tum, "tum");
  int pngs = 0, jpegs = 0;
  for (const char* sequence : {"tum/fr1_desk_9", "tum/fr3_cabinet_58kf", "ycbv_0000_10f"}) {
    const fs::path root = tum.parent_path() / sequence;
    if (!fs::exists(root)) continue;
    for (const auto& entry : fs::recursive_directory_iterator(root)) {
      const std::string ext = entry.path().extension().string();
      if (ext != ".png" && ext != ".jpg") continue;
      const std::string text = test::read_text(entry.path());
      const Bytes bytes(text.begin(), text.end());
      const cv::Mat got = ext == ".png" ? png_decoded(bytes) : jpeg_decoded(bytes);
      EXPECT_TRUE(same_pixels(got, cv::imdecode(bytes, cv::IMREAD_UNCHANGED))) << entry.path();
      ++(ext == ".png" ? pngs : jpegs);
    }
  }
  // rgb, depth and label PNGs of TUM and YCB-Video (here through libpng, not png_fast), and the
  // JPEGs of fr3_cabinet.
  EXPECT_GE(pngs, 100);
  EXPECT_GE(jpegs, 50);
}

// ---- both: no leak when the libraries jump out -----------------------------------------------

// The memory the process holds now (not its peak, which earlier tests may have raised).
long resident_kb() {
  std::ifstream statm("/proc/self/statm");
  long pages = 0, resident = 0;
  statm >> pages >> resident;
  return resident * (sysconf(_SC_PAGESIZE) / 1024);
}

TEST(DecodeErrors, LeaveNothingBehind) {
#if defined(__SANITIZE_ADDRESS__)
  // make sanitize: ASan keeps freed memory resident (its quarantine, ~300 MB here); LeakSanitizer
  // checks for leaks at exit in that build instead.
  GTEST_SKIP() << "resident memory is not a leak measure under AddressSanitizer";
#endif
  PngKind kind{"RGB 8-bit", PNG_COLOR_TYPE_RGB, 8, false, CV_8UC3};
  Bytes png = png_written(random_content(kind, 64, 64, true, 9));
  png[png.size() - 13] ^= 1;  // the last IDAT's CRC
  const Bytes jpeg = corrupt_jpeg();
  std::string error;
  for (int i = 0; i < 200; ++i) {  // the allocators' pools are warm after these
    png_decoded(png, &error);
    jpeg_decoded(jpeg, &error);
  }
  const long before = resident_kb();
  for (int i = 0; i < 5000; ++i) {
    ASSERT_TRUE(png_decoded(png, &error).empty());
    ASSERT_TRUE(jpeg_decoded(jpeg, &error).empty());
  }
  // libpng's state and zlib's window (~50 kB) and libjpeg's pools (~20 kB), leaked at each of
  // 5000 errors, would be > 300 MB.
  EXPECT_LT(resident_kb() - before, 20 * 1024);
}

// ---- through io/image.h
// ---------------------------------------------------------------------------

TEST(ReadImageFiles, JpegAndPalettePngAsRgb) {
  test::TempDir dir;
  Bytes jpeg;
  const cv::Mat colour = picture(48, 64, CV_8UC3, 31);
  ASSERT_TRUE(cv::imencode(".jpg", colour, jpeg));
  test::write_text(dir / "colour.jpg", std::string(jpeg.begin(), jpeg.end()));
  const cv::Mat from_jpeg = read_rgb(dir / "colour.jpg", 64, 48);
  EXPECT_TRUE(same_pixels(from_jpeg, cv::imdecode(jpeg, cv::IMREAD_UNCHANGED)));

  PngKind kind{"palette 4-bit tRNS", PNG_COLOR_TYPE_PALETTE, 4, true, CV_8UC4};
  const Bytes png = png_written(random_content(kind, 64, 48, false, 32));
  test::write_text(dir / "palette.png", std::string(png.begin(), png.end()));
  cv::Mat want_bgr;  // OpenCV's BGRA without its alpha
  const cv::Mat bgra = cv::imdecode(png, cv::IMREAD_UNCHANGED);
  const int from_to[] = {0, 0, 1, 1, 2, 2};
  want_bgr.create(bgra.size(), CV_8UC3);
  cv::mixChannels(&bgra, 1, &want_bgr, 1, from_to, 3);
  EXPECT_TRUE(same_pixels(read_rgb(dir / "palette.png", 64, 48), want_bgr));
  EXPECT_TRUE(same_pixels(read_image(dir / "palette.png", false), bgra));

  const cv::Mat grey = picture(48, 64, CV_8UC1, 33);
  ASSERT_TRUE(cv::imencode(".jpg", grey, jpeg));
  test::write_text(dir / "grey.jpg", std::string(jpeg.begin(), jpeg.end()));
  EXPECT_TRUE(
      same_pixels(read_image(dir / "grey.jpg", true), cv::imdecode(jpeg, cv::IMREAD_UNCHANGED)));
}

std::string read_error(const fs::path& file, bool allow_jpeg) {
  return image_checks::error_reason(file, [&] { read_image(file, allow_jpeg); });
}

TEST(ReadImageFiles, DamagedFilesAreOneLineNamingTheFile) {
  test::TempDir dir;
  const Bytes jpeg = corrupt_jpeg();
  test::write_text(dir / "bad.jpg", std::string(jpeg.begin(), jpeg.end()));
  EXPECT_EQ(read_error(dir / "bad.jpg", true),
            "cannot decode the image (libjpeg: Bogus DQT index 7); expected a PNG or JPEG image");
  EXPECT_EQ(read_error(dir / "bad.jpg", false), "not a PNG image");

  PngKind kind{"grey 4-bit", PNG_COLOR_TYPE_GRAY, 4, false, CV_8UC1};
  Bytes png = png_written(random_content(kind, 20, 20, false, 34));
  png[png.size() - 13] ^= 1;  // the IDAT chunk's CRC
  test::write_text(dir / "bad.png", std::string(png.begin(), png.end()));
  EXPECT_EQ(read_error(dir / "bad.png", false),
            "cannot decode the image (libpng: IDAT: CRC error); expected a PNG image");
  // Cut short: caught before decoding.
  test::write_text(dir / "short.png", std::string(png.begin(), png.begin() + png.size() / 2));
  EXPECT_EQ(read_error(dir / "short.png", false),
            "truncated PNG (no IEND chunk at the end); expected a PNG image");

  const Bytes cmyk = jpeg_written(picture(8, 8, CV_8UC4, 35), JCS_CMYK, JCS_CMYK, 1, 1);
  test::write_text(dir / "cmyk.jpg", std::string(cmyk.begin(), cmyk.end()));
  EXPECT_EQ(read_error(dir / "cmyk.jpg", true),
            "cannot decode the image (unsupported CMYK JPEG (4 colour components): only grey and "
            "colour (YCbCr or RGB) JPEGs are read); expected a PNG or JPEG image");
}

}  // namespace
}  // namespace objmap::io
