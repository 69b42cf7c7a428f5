#include "objmap/io/png_fast.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "io/image_checks.h"
#include "objmap/core/error.h"
#include "objmap/io/image.h"
#include "support/test_support.h"

namespace objmap::io {
namespace {

namespace fs = std::filesystem;
using image_checks::peak_rss_kb;
using image_checks::picture;
using image_checks::same_pixels;

// CRC-32 of PNG chunks (ISO 3309), to forge valid chunks below.
std::uint32_t crc32(const unsigned char* p, std::size_t n) {
  std::uint32_t c = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < n; ++i) {
    c ^= p[i];
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return c ^ 0xFFFFFFFFu;
}

std::vector<unsigned char> bytes_of(const std::string& s) { return {s.begin(), s.end()}; }

cv::Mat fast(const std::vector<unsigned char>& png) {
  return decode_png_fast(png.data(), png.size());
}

void put32(std::vector<unsigned char>& out, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) out.push_back(static_cast<unsigned char>(v >> (24 - 8 * k)));
}

void put_chunk(std::vector<unsigned char>& out, const char* type,
               const std::vector<unsigned char>& data) {
  put32(out, static_cast<std::uint32_t>(data.size()));
  std::vector<unsigned char> body(type, type + 4);
  body.insert(body.end(), data.begin(), data.end());
  out.insert(out.end(), body.begin(), body.end());
  put32(out, crc32(body.data(), body.size()));
}

// A PNG written here, row y with filter filters[y % size] (0 None, 1 Sub, 2 Up, 3 Average, 4
// Paeth), the zlib stream in stored (uncompressed) blocks: the row filters are the test's choice,
// not an encoder's.
std::vector<unsigned char> png_with_filters(const cv::Mat& image, const std::vector<int>& filters) {
  const int channels = image.channels();
  const bool wide = image.depth() == CV_16U;
  const std::size_t bpp = static_cast<std::size_t>(channels) * (wide ? 2 : 1);
  const std::size_t n = static_cast<std::size_t>(image.cols) * bpp;
  std::vector<unsigned char> raw, prev(n, 0), filtered;
  for (int y = 0; y < image.rows; ++y) {
    std::vector<unsigned char> row(n);  // PNG order: RGB(A), 16-bit big-endian
    for (int x = 0; x < image.cols; ++x)
      for (int c = 0; c < channels; ++c) {
        const int from = channels >= 3 && c < 3 ? 2 - c : c;  // BGR(A) -> RGB(A)
        const std::size_t at = (static_cast<std::size_t>(x) * channels + c) * (wide ? 2 : 1);
        if (wide) {
          const std::uint16_t v = image.ptr<std::uint16_t>(y)[x * channels + from];
          row[at] = static_cast<unsigned char>(v >> 8);
          row[at + 1] = static_cast<unsigned char>(v & 0xFF);
        } else {
          row[at] = image.ptr<std::uint8_t>(y)[x * channels + from];
        }
      }
    const int filter = filters[static_cast<std::size_t>(y) % filters.size()];
    raw.push_back(static_cast<unsigned char>(filter));
    for (std::size_t i = 0; i < n; ++i) {
      const int a = i >= bpp ? row[i - bpp] : 0, b = prev[i], c = i >= bpp ? prev[i - bpp] : 0;
      int predictor = 0;
      if (filter == 1) predictor = a;
      if (filter == 2) predictor = b;
      if (filter == 3) predictor = (a + b) / 2;
      if (filter == 4) {
        const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
        predictor = pa <= pb && pa <= pc ? a : (pb <= pc ? b : c);
      }
      raw.push_back(static_cast<unsigned char>(row[i] - predictor));
    }
    prev = row;
  }
  // zlib: header, stored blocks of at most 65535 bytes, Adler-32.
  std::vector<unsigned char> z{0x78, 0x01};
  for (std::size_t at = 0; at < raw.size(); at += 65535) {
    const std::size_t len = std::min<std::size_t>(65535, raw.size() - at);
    z.push_back(at + len == raw.size() ? 1 : 0);
    z.push_back(static_cast<unsigned char>(len & 0xFF));
    z.push_back(static_cast<unsigned char>(len >> 8));
    z.push_back(static_cast<unsigned char>(~len & 0xFF));
    z.push_back(static_cast<unsigned char>((~len >> 8) & 0xFF));
    z.insert(z.end(), raw.begin() + at, raw.begin() + at + len);
  }
  std::uint32_t s1 = 1, s2 = 0;
  for (unsigned char v : raw) {
    s1 = (s1 + v) % 65521;
    s2 = (s2 + s1) % 65521;
  }
  put32(z, (s2 << 16) | s1);
  std::vector<unsigned char> png{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  std::vector<unsigned char> ihdr;
  put32(ihdr, static_cast<std::uint32_t>(image.cols));
  put32(ihdr, static_cast<std::uint32_t>(image.rows));
  ihdr.push_back(wide ? 16 : 8);
  ihdr.push_back(static_cast<unsigned char>(channels == 1 ? 0 : channels == 3 ? 2 : 6));
  ihdr.insert(ihdr.end(), {0, 0, 0});
  put_chunk(png, "IHDR", ihdr);
  // The image data in two IDAT chunks (a decoder must join them).
  const std::size_t half = z.size() / 2;
  put_chunk(png, "IDAT", std::vector<unsigned char>(z.begin(), z.begin() + half));
  put_chunk(png, "IDAT", std::vector<unsigned char>(z.begin() + half, z.end()));
  put_chunk(png, "IEND", {});
  return png;
}

TEST(PngFast, EveryRowFilterAsOpenCvDecodesIt) {
  // Each filter after each other one; Sub rows followed by rows that do and do not read the row
  // above (the decoder takes a one-pass path for a Sub row when the next row does not need it).
  const std::vector<std::vector<int>> patterns{{0, 1, 2, 3, 4},
                                               {1, 1, 0, 1, 3, 1, 4, 1, 1, 2, 2, 4, 4, 3, 3, 0, 0}};
  for (const auto& filters : patterns) {
    for (int type : {CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1}) {
      const cv::Mat image = picture(41, 300, type, 5u + type);  // rows > 64 kB of stored data
      const std::vector<unsigned char> png = png_with_filters(image, filters);
      const cv::Mat want = cv::imdecode(png, cv::IMREAD_UNCHANGED);
      ASSERT_TRUE(same_pixels(want, image)) << "the test's own PNG, type " << type;
      const cv::Mat got = fast(png);
      ASSERT_FALSE(got.empty()) << "type " << type;
      EXPECT_TRUE(same_pixels(got, want))
          << "type " << type << ", " << filters.size() << " filters";
    }
  }
}

TEST(PngFast, SamePixelsAsOpenCvForEveryTypeItTakes) {
  for (int type : {CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1}) {
    for (int strategy : {cv::IMWRITE_PNG_STRATEGY_DEFAULT, cv::IMWRITE_PNG_STRATEGY_FILTERED,
                         cv::IMWRITE_PNG_STRATEGY_RLE}) {
      for (int compression : {0, 3, 9}) {
        const cv::Mat image = picture(37, 53, type, 17u + type);
        std::vector<unsigned char> png;
        ASSERT_TRUE(cv::imencode(
            ".png", image, png,
            {cv::IMWRITE_PNG_STRATEGY, strategy, cv::IMWRITE_PNG_COMPRESSION, compression}));
        const cv::Mat got = fast(png);
        ASSERT_FALSE(got.empty()) << "type " << type << " strategy " << strategy;
        EXPECT_TRUE(same_pixels(got, cv::imdecode(png, cv::IMREAD_UNCHANGED)))
            << "type " << type << " strategy " << strategy << " compression " << compression;
        EXPECT_TRUE(same_pixels(got, image));
      }
    }
  }
}

TEST(PngFast, SamePixelsAsOpenCvOnTheRealRecordings) {
  OBJMAP_DATA_OR_SKIP(data, "tum");
  const fs::path ycbv = data.parent_path() / "ycbv_0000_10f";
  std::vector<fs::path> files;
  for (const fs::path& dir :
       {data / "fr1_desk_9/rgb", data / "fr1_desk_9/depth", data / "fr3_cabinet_58kf/depth",
        ycbv / "rgb", ycbv / "depth", ycbv / "masks"}) {
    if (!fs::exists(dir)) continue;
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path().extension() == ".png") files.push_back(e.path());
  }
  ASSERT_GE(files.size(), 30u);
  int decoded_here = 0;
  for (const fs::path& f : files) {
    const auto png = bytes_of(test::read_text(f));
    const cv::Mat got = fast(png);
    const cv::Mat want = cv::imdecode(png, cv::IMREAD_UNCHANGED);
    if (got.empty()) continue;  // left to libpng (io/codecs.h): allowed, counted below
    ++decoded_here;
    EXPECT_TRUE(same_pixels(got, want)) << f;
  }
  // TUM and YCB-Video PNGs (8-bit RGB, 16-bit depth, 8-bit labels) are all decoded here.
  EXPECT_EQ(decoded_here, static_cast<int>(files.size()));
}

// A 16-bit grey PNG whose header claims 30000 x 30000 pixels (1.8 GB) over 11 bytes of data.
std::vector<unsigned char> huge_claim() {
  std::vector<unsigned char> png{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  std::vector<unsigned char> ihdr;
  put32(ihdr, 30000);
  put32(ihdr, 30000);
  ihdr.insert(ihdr.end(), {16, 0, 0, 0, 0});
  put_chunk(png, "IHDR", ihdr);
  put_chunk(png, "IDAT", {0x78, 0x01, 0x01, 0x00, 0x00, 0xff, 0xff, 0, 0, 0, 1});
  put_chunk(png, "IEND", {});
  return png;
}

TEST(PngFast, ImagesOfTheWrongSizeAreRefusedFromTheirHeader) {
  // read_depth checks the header's size before decoding: one clear line, no 1.8 GB image made
  // (OpenCV would make it before finding the data short).
  test::TempDir dir;
  const std::vector<unsigned char> png = huge_claim();
  test::write_text(dir / "huge.png", std::string(png.begin(), png.end()));
  const long peak_before = peak_rss_kb();
  try {
    read_depth(dir / "huge.png", 640, 480);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), (dir / "huge.png").string());
    EXPECT_EQ(e.reason(), "image is 30000x30000; expected 640x480 (the camera's width x height)");
  }
  EXPECT_LT(peak_rss_kb() - peak_before, 100 * 1024);
}

TEST(PngFast, LeavesOtherPngsAndDamageToLibpng) {
  const cv::Mat depth = picture(20, 30, CV_16UC1, 3);
  std::vector<unsigned char> png;
  ASSERT_TRUE(cv::imencode(".png", depth, png));
  ASSERT_FALSE(fast(png).empty());

  // 16-bit colour, grey + alpha: not decoded here.
  std::vector<unsigned char> rgb16;
  ASSERT_TRUE(cv::imencode(".png", picture(8, 8, CV_16UC3, 4), rgb16));
  EXPECT_TRUE(fast(rgb16).empty());
  EXPECT_FALSE(cv::imdecode(rgb16, cv::IMREAD_UNCHANGED).empty());

  // Not a PNG, too short, truncated.
  EXPECT_TRUE(fast({'h', 'e', 'l', 'l', 'o'}).empty());
  EXPECT_TRUE(fast(std::vector<unsigned char>(png.begin(), png.begin() + 40)).empty());
  EXPECT_TRUE(fast(std::vector<unsigned char>(png.begin(), png.end() - 12)).empty());

  // A flipped bit in the image data: the chunk CRC no longer matches.
  const std::size_t idat = std::string(png.begin(), png.end()).find("IDAT");
  ASSERT_NE(idat, std::string::npos);
  std::vector<unsigned char> flipped = png;
  flipped[idat + 10] ^= 0x10;
  EXPECT_TRUE(fast(flipped).empty());

  // An unknown critical chunk (upper-case first letter) before IEND: left to libpng.
  {
    std::vector<unsigned char> critical(png.begin(), png.end() - 12);
    put_chunk(critical, "ZZZZ", {1, 2, 3});
    put_chunk(critical, "IEND", {});
    EXPECT_TRUE(fast(critical).empty());
    std::vector<unsigned char> ancillary(png.begin(), png.end() - 12);
    put_chunk(ancillary, "zzZz", {1, 2, 3});  // ancillary: skipped
    put_chunk(ancillary, "IEND", {});
    EXPECT_TRUE(same_pixels(fast(ancillary), depth));
  }

  // A header that claims 30000 x 30000 pixels over a few bytes of data: refused before any
  // buffer of that size is made (libpng then reports the file).
  {
    const std::vector<unsigned char> huge = huge_claim();
    const long peak_before = peak_rss_kb();
    EXPECT_TRUE(fast(huge).empty());
    // 30000 x 30000 x 2 bytes would be 1.8 GB; a peak that grew by more than 100 MB means a
    // buffer of the claimed size was made.
    EXPECT_LT(peak_rss_kb() - peak_before, 100 * 1024);
  }

  // Interlaced (Adam7) with a valid IHDR CRC: not decoded here.
  std::vector<unsigned char> interlaced = png;
  interlaced[8 + 8 + 12] = 1;                                   // the IHDR's interlace byte
  const std::uint32_t crc = crc32(interlaced.data() + 12, 17);  // "IHDR" + 13 bytes
  for (int k = 0; k < 4; ++k)
    interlaced[8 + 8 + 13 + k] = static_cast<unsigned char>(crc >> (24 - 8 * k));
  EXPECT_TRUE(fast(interlaced).empty());
  // The same forging without the change keeps the file valid (the CRC above is right).
  std::vector<unsigned char> same = png;
  const std::uint32_t same_crc = crc32(same.data() + 12, 17);
  for (int k = 0; k < 4; ++k)
    same[8 + 8 + 13 + k] = static_cast<unsigned char>(same_crc >> (24 - 8 * k));
  EXPECT_TRUE(same_pixels(fast(same), depth));
}

}  // namespace
}  // namespace objmap::io
