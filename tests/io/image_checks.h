#pragma once
// Helpers of the image reading tests (image_test.cpp, png_fast_test.cpp, codecs_test.cpp).
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>

#include <opencv2/core.hpp>

#include "objmap/core/error.h"

namespace objmap::io::image_checks {

// The reason of the InputError that read() throws; the error must name `file`.
template <typename Read>
std::string error_reason(const std::filesystem::path& file, Read&& read) {
  try {
    read();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), file.string());
    return e.reason();
  }
  ADD_FAILURE() << "no error for " << file;
  return "";
}

inline long peak_rss_kb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;
}

// Same type, size and every byte.
inline ::testing::AssertionResult same_pixels(const cv::Mat& a, const cv::Mat& b) {
  if (a.type() != b.type() || a.size() != b.size())
    return ::testing::AssertionFailure()
           << "type/size " << a.type() << " " << a.size() << " vs " << b.type() << " " << b.size();
  for (int y = 0; y < a.rows; ++y)
    if (std::memcmp(a.ptr(y), b.ptr(y), a.cols * a.elemSize()) != 0)
      return ::testing::AssertionFailure() << "row " << y << " differs";
  return ::testing::AssertionSuccess();
}

// A smooth, noisy picture: libpng's adaptive filter choice (OpenCV's encoder) then picks among all
// five row filters, None, Sub, Up, Average and Paeth, row by row.
inline cv::Mat picture(int rows, int cols, int type, std::uint64_t seed) {
  cv::Mat m(rows, cols, type);
  cv::RNG rng(seed);
  const int channels = m.channels();
  const double scale = m.depth() == CV_16U ? 60000.0 : 250.0;
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x)
      for (int c = 0; c < channels; ++c) {
        const double v = 0.5 + 0.4 * std::sin(0.05 * x * (c + 1) + 0.03 * y) + rng.gaussian(0.03);
        const double clamped = std::min(1.0, std::max(0.0, v)) * scale;
        if (m.depth() == CV_16U)
          m.ptr<std::uint16_t>(y)[x * channels + c] = static_cast<std::uint16_t>(clamped);
        else
          m.ptr<std::uint8_t>(y)[x * channels + c] = static_cast<std::uint8_t>(clamped);
      }
  return m;
}

}  // namespace objmap::io::image_checks
