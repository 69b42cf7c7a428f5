#include "objmap/io/image.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <system_error>
#include <vector>

#include <opencv2/core.hpp>

#include "objmap/core/error.h"
#include "objmap/io/codecs.h"
#include "objmap/io/library_errors.h"
#include "objmap/io/png_fast.h"

namespace objmap::io {

namespace fs = std::filesystem;

namespace {

enum class Format { kPng, kJpeg, kOther };

Format format_of(const std::vector<unsigned char>& bytes) {
  static const unsigned char kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (bytes.size() >= 8 && std::memcmp(bytes.data(), kPng, 8) == 0) return Format::kPng;
  if (bytes.size() >= 3 && bytes[0] == 0xFF && bytes[1] == 0xD8 && bytes[2] == 0xFF)
    return Format::kJpeg;
  return Format::kOther;
}

// A complete PNG ends with the IEND chunk (length 0, "IEND", its CRC AE 42 60 82).
bool png_complete(const std::vector<unsigned char>& bytes) {
  static const unsigned char kIend[12] = {0, 0, 0, 0, 'I', 'E', 'N', 'D', 0xAE, 0x42, 0x60, 0x82};
  return bytes.size() >= 8 + 12 &&
         std::memcmp(bytes.data() + bytes.size() - 12, kIend, sizeof(kIend)) == 0;
}

// A complete JPEG ends with the EOI marker FF D9 (a few padding bytes after it are tolerated).
bool jpeg_complete(const std::vector<unsigned char>& bytes) {
  const std::size_t tail = std::min<std::size_t>(bytes.size(), 64);
  for (std::size_t i = bytes.size() - tail; i + 1 < bytes.size(); ++i)
    if (bytes[i] == 0xFF && bytes[i + 1] == 0xD9) return true;
  return false;
}

std::vector<unsigned char> read_bytes(const fs::path& file) {
  std::error_code ec;
  if (!fs::exists(file, ec)) throw InputError(file.string(), "image file not found");
  if (!fs::is_regular_file(file, ec)) throw InputError(file.string(), "is not a file");
  std::ifstream in(file, std::ios::binary | std::ios::ate);
  if (!in) throw InputError(file.string(), "cannot open the image file for reading");
  const std::streamoff size = in.tellg();
  if (size < 0) throw InputError(file.string(), "read error");
  std::vector<unsigned char> bytes(static_cast<std::size_t>(size));
  in.seekg(0);
  in.read(reinterpret_cast<char*>(bytes.data()), size);
  if (in.gcount() != size) throw InputError(file.string(), "read error");
  if (bytes.empty()) throw InputError(file.string(), "empty file; expected an image");
  return bytes;
}

void check_size(const fs::path& file, long cols, long rows, int width, int height) {
  if ((width > 0 && cols != width) || (height > 0 && rows != height))
    throw InputError(file.string(), "image is " + std::to_string(cols) + "x" +
                                        std::to_string(rows) + "; expected " +
                                        std::to_string(width) + "x" + std::to_string(height) +
                                        " (the camera's width x height)");
}

// width/height > 0: the size required; a PNG's or JPEG's header is checked before the image is
// decoded (a header claiming a huge image costs no memory and no time).
cv::Mat decode(const fs::path& file, const std::vector<unsigned char>& bytes, bool allow_jpeg,
               int width, int height) {
  const Format format = format_of(bytes);
  const std::string expected = allow_jpeg ? "a PNG or JPEG image" : "a PNG image";
  if (format == Format::kOther || (format == Format::kJpeg && !allow_jpeg))
    throw InputError(file.string(), "not " + expected);
  if (format == Format::kPng && !png_complete(bytes))
    throw InputError(file.string(),
                     "truncated PNG (no IEND chunk at the end); expected " + expected);
  if (format == Format::kJpeg && !jpeg_complete(bytes))
    throw InputError(file.string(), "truncated JPEG (no end marker); expected " + expected);
  std::uint32_t header_width = 0, header_height = 0;
  if ((format == Format::kPng &&
       png_size(bytes.data(), bytes.size(), header_width, header_height)) ||
      (format == Format::kJpeg &&
       jpeg_size(bytes.data(), bytes.size(), header_width, header_height)))
    check_size(file, header_width, header_height, width, height);
  // The PNGs of RGB-D recordings go through the faster decoder (same pixels); the other PNGs, and
  // any PNG it refuses (also a damaged one: libpng then says what is wrong), through libpng.
  if (format == Format::kPng) {
    cv::Mat image = decode_png_fast(bytes.data(), bytes.size());
    if (!image.empty()) return image;
  }
  std::string error;
  cv::Mat image = format == Format::kPng ? decode_png(bytes.data(), bytes.size(), error)
                                         : decode_jpeg(bytes.data(), bytes.size(), error);
  if (image.empty())
    throw InputError(file.string(),
                     "cannot decode the image (" + error + "); expected " + expected);
  return image;
}

std::string depth_name(int depth) {
  switch (depth) {
    case CV_8U:
      return "8-bit";
    case CV_8S:
      return "signed 8-bit";
    case CV_16U:
      return "16-bit";
    case CV_16S:
      return "signed 16-bit";
    case CV_32S:
      return "32-bit integer";
    case CV_32F:
      return "32-bit float";
    case CV_64F:
      return "64-bit float";
    default:
      return "unusual";
  }
}

}  // namespace

cv::Mat read_image(const fs::path& file, bool allow_jpeg) {
  try {
    return decode(file, read_bytes(file), allow_jpeg, 0, 0);
  } catch (...) {
    rethrow_naming_file(file.string());
  }
}

namespace {

cv::Mat rgb_of(const fs::path& file, int width, int height) {
  const cv::Mat image = decode(file, read_bytes(file), /*allow_jpeg=*/true, width, height);
  if (image.depth() != CV_8U)
    throw InputError(file.string(),
                     depth_name(image.depth()) + " colour image; expected 8 bits per channel");
  check_size(file, image.cols, image.rows, width, height);
  if (image.channels() == 3) return image;
  cv::Mat bgr(image.rows, image.cols, CV_8UC3);
  if (image.channels() == 1) {
    const int from_to[] = {0, 0, 0, 1, 0, 2};
    cv::mixChannels(&image, 1, &bgr, 1, from_to, 3);
  } else if (image.channels() == 4) {
    const int from_to[] = {0, 0, 1, 1, 2, 2};  // drop alpha
    cv::mixChannels(&image, 1, &bgr, 1, from_to, 3);
  } else {
    throw InputError(file.string(), std::to_string(image.channels()) +
                                        " channels; expected a colour (or grey) image");
  }
  return bgr;
}

cv::Mat depth_of(const fs::path& file, int width, int height) {
  const cv::Mat image = decode(file, read_bytes(file), /*allow_jpeg=*/false, width, height);
  if (image.channels() != 1)
    throw InputError(file.string(), std::to_string(image.channels()) +
                                        "-channel (colour) image; expected a 16-bit single-channel "
                                        "depth PNG");
  if (image.depth() != CV_16U)
    throw InputError(file.string(), depth_name(image.depth()) +
                                        " image; expected a 16-bit single-channel depth PNG "
                                        "(metres x depth_factor)");
  check_size(file, image.cols, image.rows, width, height);
  return image;
}

}  // namespace

// OpenCV's exceptions (a Mat that cannot be allocated, a conversion) name the file too.
cv::Mat read_rgb(const fs::path& file, int width, int height) {
  try {
    return rgb_of(file, width, height);
  } catch (...) {
    rethrow_naming_file(file.string());
  }
}

cv::Mat read_depth(const fs::path& file, int width, int height) {
  try {
    return depth_of(file, width, height);
  } catch (...) {
    rethrow_naming_file(file.string());
  }
}

}  // namespace objmap::io
