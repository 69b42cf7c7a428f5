#pragma once
#include <cstddef>
#include <cstdint>

#include <opencv2/core/mat.hpp>

// A PNG decoder for the images of RGB-D recordings (TUM RGB-D, YCB-Video, objmap synth): libdeflate
// inflates the image data in one call and the rows are unfiltered here. It takes non-interlaced
// 8-bit grey, RGB and RGBA and 16-bit grey without a tRNS chunk, and gives exactly the pixels of
// cv::imdecode(IMREAD_UNCHANGED) (BGR(A) order, 16-bit in host order). Anything else, and any
// damage it finds (bad chunk CRC, bad zlib stream or Adler-32, wrong data size, unknown row
// filter), gives an empty Mat: the caller then decodes with libpng (io/codecs.h), which reports
// the error.
namespace objmap::io {

cv::Mat decode_png_fast(const unsigned char* data, std::size_t size);

// The width and height in a PNG's header (its first chunk, IHDR), read without decoding; false
// when the bytes do not start with a PNG signature and an IHDR chunk.
bool png_size(const unsigned char* data, std::size_t size, std::uint32_t& width,
              std::uint32_t& height);

}  // namespace objmap::io
