// The JPEG decoder (io/codecs.h, libjpeg) in memory: an image, or an empty Mat with a message.
#include <cstddef>
#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

#include "fuzz_util.h"
#include "objmap/io/codecs.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string error;
  const cv::Mat image = objmap::io::decode_jpeg(data, size, error);
  if (image.empty() && error.empty()) objmap::fuzz::finding("decode_jpeg: no image and no message");
  if (!image.empty() && image.type() != CV_8UC1 && image.type() != CV_8UC3)
    objmap::fuzz::finding("decode_jpeg: a Mat of type " + std::to_string(image.type()));
  return 0;
}
