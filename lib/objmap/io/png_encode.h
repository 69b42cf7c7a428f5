#pragma once
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

// A small, fast PNG encoder (the synthetic sequences, the report's pictures): one filter for every
// row (Sub) and zlib level 1 run-length deflate. Several times faster than libpng's adaptive
// filters; the files are valid PNGs of the same pixels (any reader, e.g. cv::imread, gives the
// image back exactly).
namespace objmap::io {

// PNG bytes of `image` into `png` (replaced; its capacity is reused): CV_8UC3 (BGR, OpenCV order;
// stored as RGB), CV_8UC1 or CV_16UC1 (stored big-endian). Throws InputError("encode_png", ...)
// for another type or an empty image.
void encode_png(const cv::Mat& image, std::vector<std::uint8_t>* png);

}  // namespace objmap::io
