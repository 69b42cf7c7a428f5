#pragma once
#include <filesystem>

#include <opencv2/core/mat.hpp>

// Strict image loading: the PNGs of RGB-D recordings by io/png_fast.h (libdeflate), the rest by
// io/codecs.h (libpng, libjpeg); either way the pixels cv::imread(IMREAD_UNCHANGED) would give. A
// file that is missing, truncated (a PNG without its IEND chunk, a JPEG without its end marker),
// undecodable, of another size or of the wrong pixel type is an InputError naming the file and what
// was expected: OpenCV would otherwise return an empty or silently padded image.
namespace objmap::io {

// Any PNG (or JPEG when allow_jpeg) as cv::imread(file, IMREAD_UNCHANGED) gives it: the file's
// channels (BGR(A) order; a palette expanded, a tRNS chunk of a colour image as alpha) and bit
// depth (16-bit values in host order). Any size; the checks above apply.
cv::Mat read_image(const std::filesystem::path& file, bool allow_jpeg);

// A colour image as CV_8UC3 BGR. PNG or JPEG, 8-bit; a grey image is expanded to three channels and
// an alpha channel dropped. width/height > 0 are required sizes (0 = any size).
cv::Mat read_rgb(const std::filesystem::path& file, int width, int height);

// A depth image as CV_16UC1 raw values (metres = value / camera.depth_factor, 0 = no depth). Must
// be a 16-bit single-channel PNG; width/height > 0 are required sizes (0 = any size).
cv::Mat read_depth(const std::filesystem::path& file, int width, int height);

}  // namespace objmap::io
