// The JPEG decoder (io/codecs.h, libjpeg) in memory: an image, or an empty Mat with a message.
#include <cstddef>
#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

#include "fuzz_util.h"
#include "objmap/io/codecs.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  std::uint32_t width = 0, height = 0;
  if (io::jpeg_size(data, size, width, height) && fuzz::too_many_pixels(width, height)) return 0;
  std::string error;
  const cv::Mat image = io::decode_jpeg(data, size, error);
  if (image.empty() && error.empty()) fuzz::finding("decode_jpeg: no image and no message");
  if (!image.empty() && image.type() != CV_8UC1 && image.type() != CV_8UC3)
    fuzz::finding("decode_jpeg: a Mat of type " + std::to_string(image.type()));
  return 0;
}
