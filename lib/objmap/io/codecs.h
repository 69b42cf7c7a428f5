#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

#include <opencv2/core/mat.hpp>

// PNG decoding on libpng and JPEG decoding on libjpeg(-turbo), giving the Mat that OpenCV 4.6's
// cv::imdecode(bytes, IMREAD_UNCHANGED) gives (OpenCV uses the same two libraries with the same
// settings): BGR(A) channel order, 16-bit values in host order. These two libraries load in well
// under a millisecond, where OpenCV's imgcodecs brings GDAL and ~115 shared libraries (~100 ms at
// the start of every objmap command). io::read_rgb/read_depth/read_image (image.h) use them for
// what io/png_fast.h does not take. Errors of the libraries (their longjmp) end here: on failure
// the result is an empty Mat and `error` says what is wrong in one line; nothing is leaked.
namespace objmap::io {

// Any PNG: grey 1/2/4/8/16-bit -> CV_8UC1 / CV_16UC1 (1/2/4-bit scaled to 0..255, a tRNS chunk
// ignored); RGB -> CV_8UC3 / CV_16UC3 BGR, or BGRA (CV_8UC4 / CV_16UC4) when a tRNS chunk makes a
// colour transparent (alpha 0 there, else the maximum); palette -> BGR, or BGRA with a tRNS chunk;
// grey + alpha -> BGRA with B = G = R = grey; RGBA -> BGRA. Interlaced images too.
cv::Mat decode_png(const unsigned char* data, std::size_t size, std::string& error);

// A JPEG (baseline, progressive or arithmetic-coded; 8-bit samples) with one component (grey,
// CV_8UC1) or three (YCbCr or RGB, CV_8UC3 BGR). A CMYK or YCCK JPEG (four components, which
// OpenCV would convert) is an error here.
cv::Mat decode_jpeg(const unsigned char* data, std::size_t size, std::string& error);

// The width and height in a JPEG's header (its frame marker), read without decoding; false when
// libjpeg cannot read the header.
bool jpeg_size(const unsigned char* data, std::size_t size, std::uint32_t& width,
               std::uint32_t& height);

}  // namespace objmap::io
