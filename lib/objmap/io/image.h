#pragma once
#include <filesystem>

#include <opencv2/core/mat.hpp>

// Strict image loading: the PNGs of RGB-D recordings by io/png_fast.h (libdeflate, the same
// pixels), the rest by OpenCV imgcodecs. A file that is missing, truncated (a PNG without its IEND
// chunk, a JPEG without its end marker), undecodable, of another size or of the wrong pixel type is
// an InputError naming the file and what was expected: OpenCV would otherwise return an empty or
// silently padded image.
namespace objmap::io {

// A colour image as CV_8UC3 BGR. PNG or JPEG, 8-bit; a grey image is expanded to three channels and
// an alpha channel dropped. width/height > 0 are required sizes (0 = any size).
cv::Mat read_rgb(const std::filesystem::path& file, int width, int height);

// A depth image as CV_16UC1 raw values (metres = value / camera.depth_factor, 0 = no depth). Must
// be a 16-bit single-channel PNG; width/height > 0 are required sizes (0 = any size).
cv::Mat read_depth(const std::filesystem::path& file, int width, int height);

}  // namespace objmap::io
