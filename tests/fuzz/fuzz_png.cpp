// objmap's own PNG decoder (io/png_fast.h, hand-written over libdeflate) against libpng
// (io/codecs.h) on the same bytes, in memory: neither may fail other than by an empty Mat with
// (for libpng) a message, and an image that png_fast decodes must come out of libpng with exactly
// the same type, size and pixels.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include <opencv2/core.hpp>

#include "fuzz_util.h"
#include "objmap/io/codecs.h"
#include "objmap/io/png_fast.h"

namespace {

bool same_pixels(const cv::Mat& a, const cv::Mat& b) {
  if (a.type() != b.type() || a.size() != b.size()) return false;
  const std::size_t row = a.cols * a.elemSize();
  for (int y = 0; y < a.rows; ++y)
    if (std::memcmp(a.ptr(y), b.ptr(y), row) != 0) return false;
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  std::uint32_t width = 0, height = 0;
  const bool has_header = io::png_size(data, size, width, height);
  const cv::Mat fast = io::decode_png_fast(data, size);
  std::string error;
  const cv::Mat slow = io::decode_png(data, size, error);
  if (slow.empty() && error.empty()) fuzz::finding("decode_png: no image and no error message");
  if (fast.empty()) return 0;
  if (!has_header || fast.cols != static_cast<int>(width) || fast.rows != static_cast<int>(height))
    fuzz::finding("png_size disagrees with decode_png_fast");
  if (slow.empty()) fuzz::finding("decode_png_fast decoded a PNG that libpng refuses: " + error);
  if (!same_pixels(fast, slow)) fuzz::finding("decode_png_fast and libpng give different pixels");
  return 0;
}
