#pragma once
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "objmap/io/png_encode.h"

// The 8x6 colour and depth PNGs the layout targets put in their folders (objmap's own encoder).
namespace objmap::fuzz {

inline std::string png_of(const cv::Mat& image) {
  std::vector<std::uint8_t> png;
  io::encode_png(image, &png);
  return std::string(png.begin(), png.end());
}

inline const std::string& tiny_color_png() {
  static const std::string png = png_of(cv::Mat(6, 8, CV_8UC3, cv::Scalar(1, 2, 3)));
  return png;
}

inline const std::string& tiny_depth_png() {
  static const std::string png = png_of(cv::Mat(6, 8, CV_16UC1, cv::Scalar(1000)));
  return png;
}

}  // namespace objmap::fuzz
