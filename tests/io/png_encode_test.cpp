// objmap's fast PNG encoder (synthetic images, report pictures): any reader gives the exact pixels
// back.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "objmap/core/error.h"
#include "objmap/io/png_encode.h"

namespace objmap::io {
namespace {

// Noise, flat areas and steps (what the filter and the run-length coding see), odd sizes.
cv::Mat test_image(int type, std::uint64_t seed) {
  cv::Mat image(31, 45, type);
  cv::RNG rng(seed);
  const int channels = image.channels();
  for (int v = 0; v < image.rows; ++v)
    for (int u = 0; u < image.cols; ++u)
      for (int c = 0; c < channels; ++c) {
        const double r = rng.uniform(0.0, 1.0);
        const int value = u < 10 ? 0 : (r < 0.5 ? 40 * c + 3 * v : static_cast<int>(r * 65535));
        if (image.depth() == CV_16U)
          image.ptr<std::uint16_t>(v)[u * channels + c] = static_cast<std::uint16_t>(value);
        else
          image.ptr<std::uint8_t>(v)[u * channels + c] = static_cast<std::uint8_t>(value & 255);
      }
  return image;
}

TEST(PngEncode, DecodesToTheExactPixels) {
  std::vector<std::uint8_t> bytes;
  for (int type : {CV_8UC3, CV_8UC1, CV_16UC1}) {
    const cv::Mat image = test_image(type, 11 + type);
    encode_png(image, &bytes);  // the buffer is reused from one image to the next
    ASSERT_GT(bytes.size(), 8u);
    const cv::Mat decoded = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);  // BGR, like imread
    ASSERT_EQ(decoded.type(), type);
    ASSERT_EQ(decoded.size(), image.size());
    EXPECT_EQ(cv::norm(decoded, image, cv::NORM_INF), 0.0) << "type " << type;
  }
}

TEST(PngEncode, RefusesOtherTypes) {
  std::vector<std::uint8_t> bytes;
  try {
    encode_png(cv::Mat(4, 4, CV_32FC1, cv::Scalar::all(1.0)), &bytes);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("expected CV_8UC3, CV_8UC1 or CV_16UC1"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace objmap::io
