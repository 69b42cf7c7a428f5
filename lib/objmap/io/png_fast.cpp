#include "objmap/io/png_fast.h"

#include <libdeflate.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include <opencv2/core.hpp>

#include "objmap/io/deflate.h"

namespace objmap::io {

namespace {

std::uint32_t be32(const unsigned char* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}

// One scratch buffer per thread (fuse decodes on every worker; the decompressor is deflate.h's,
// one per thread too).
struct Scratch {
  std::vector<unsigned char> idat;      // the concatenated IDAT payloads
  std::vector<unsigned char> filtered;  // inflated: per row a filter byte and the row's bytes
};

int paeth(int a, int b, int c) {
  const int p = a + b - c;
  const int pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  if (pa <= pb && pa <= pc) return a;
  return pb <= pc ? b : c;
}

// Undoes the row filter of `row` (n bytes, bpp bytes per pixel) in place; `prev` is the previous
// row already unfiltered, or nullptr for the first row (all zero). False for an unknown filter.
bool unfilter(int filter, unsigned char* row, const unsigned char* prev, std::size_t n,
              std::size_t bpp) {
  switch (filter) {
    case 0:  // None
      return true;
    case 1:  // Sub
      for (std::size_t i = bpp; i < n; ++i)
        row[i] = static_cast<unsigned char>(row[i] + row[i - bpp]);
      return true;
    case 2:  // Up
      if (prev)
        for (std::size_t i = 0; i < n; ++i) row[i] = static_cast<unsigned char>(row[i] + prev[i]);
      return true;
    case 3:  // Average
      for (std::size_t i = 0; i < n; ++i) {
        const int left = i >= bpp ? row[i - bpp] : 0;
        const int up = prev ? prev[i] : 0;
        row[i] = static_cast<unsigned char>(row[i] + ((left + up) >> 1));
      }
      return true;
    case 4:  // Paeth
      for (std::size_t i = 0; i < n; ++i) {
        const int left = i >= bpp ? row[i - bpp] : 0;
        const int up = prev ? prev[i] : 0;
        const int up_left = prev && i >= bpp ? prev[i - bpp] : 0;
        row[i] = static_cast<unsigned char>(row[i] + paeth(left, up, up_left));
      }
      return true;
    default:
      return false;
  }
}

// A Sub-filtered row (the filter of every row of TUM RGB-D's PNGs) unfiltered straight into
// OpenCV's layout, each channel's running sum in a register: one pass, no stores to reload.
template <int kChannels>
void sub_row_8bit(const unsigned char* src, unsigned char* dst, std::size_t width) {
  unsigned char sum[kChannels] = {};
  for (std::size_t x = 0; x < width; ++x) {
    for (int c = 0; c < kChannels; ++c) sum[c] = static_cast<unsigned char>(sum[c] + src[c]);
    if constexpr (kChannels >= 3) {
      dst[0] = sum[2];
      dst[1] = sum[1];
      dst[2] = sum[0];
      if constexpr (kChannels == 4) dst[3] = sum[3];
    } else {
      dst[0] = sum[0];
    }
    src += kChannels;
    dst += kChannels;
  }
}

void sub_row_16bit(const unsigned char* src, std::uint16_t* dst, std::size_t width) {
  unsigned char hi = 0, lo = 0;  // PNG filters work on bytes: no carry from the low byte
  for (std::size_t x = 0; x < width; ++x) {
    hi = static_cast<unsigned char>(hi + src[2 * x]);
    lo = static_cast<unsigned char>(lo + src[2 * x + 1]);
    dst[x] = static_cast<std::uint16_t>((hi << 8) | lo);
  }
}

const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

// The fields of IHDR that decide the pixel layout.
struct Header {
  std::uint32_t width = 0, height = 0;
  int bit_depth = 0, colour_type = -1;
};

// 1. Chunks: IHDR first, the IDATs concatenated into `idat`, up to IEND; every CRC checked. False
//    for a broken file and for what this decoder leaves to io/codecs.h.
bool read_chunks(const unsigned char* data, std::size_t size, Header& header,
                 std::vector<unsigned char>& idat) {
  bool ended = false;
  idat.clear();
  std::size_t pos = 8;
  while (pos + 12 <= size) {
    const std::uint32_t length = be32(data + pos);
    if (length > size - pos - 12) return false;
    const unsigned char* type = data + pos + 4;
    const unsigned char* payload = data + pos + 8;
    const std::uint32_t crc = be32(payload + length);
    if (libdeflate_crc32(0, type, length + 4) != crc) return false;
    const bool first = pos == 8;
    pos += 12 + std::size_t{length};
    if (first != (std::memcmp(type, "IHDR", 4) == 0)) return false;
    if (first) {
      if (length != 13) return false;
      header.width = be32(payload);
      header.height = be32(payload + 4);
      header.bit_depth = payload[8];
      header.colour_type = payload[9];
      // Compression 0, filter method 0, no interlace.
      if (payload[10] != 0 || payload[11] != 0 || payload[12] != 0) return false;
    } else if (std::memcmp(type, "IDAT", 4) == 0) {
      idat.insert(idat.end(), payload, payload + length);
    } else if (std::memcmp(type, "IEND", 4) == 0) {
      ended = true;
      break;
    } else if (std::memcmp(type, "tRNS", 4) == 0 || std::memcmp(type, "PLTE", 4) == 0) {
      return false;  // OpenCV turns transparency into an alpha channel: left to io/codecs.h
    } else if ((type[0] & 0x20) == 0) {
      return false;  // an unknown critical chunk (upper-case first letter): not ours to skip
    }
    // Ancillary chunks (gAMA, pHYs, text, ...) do not change the pixels OpenCV gives.
  }
  return ended && !idat.empty();
}

// 2. The pixel types decoded here, as cv::imdecode(IMREAD_UNCHANGED) returns them: the channel
//    count, or 0 for a type or size left to io/codecs.h.
int channels_of(const Header& header) {
  int channels = 0;
  if (header.bit_depth == 8 && header.colour_type == 0)
    channels = 1;
  else if (header.bit_depth == 8 && header.colour_type == 2)
    channels = 3;
  else if (header.bit_depth == 8 && header.colour_type == 6)
    channels = 4;
  else if (header.bit_depth == 16 && header.colour_type == 0)
    channels = 1;
  else
    return 0;
  if (header.width == 0 || header.height == 0 || header.width > (1u << 15) ||
      header.height > (1u << 15))
    return 0;
  return channels;
}

// 3. Inflate (zlib stream, Adler-32 checked) to exactly `filtered_bytes`. Deflate expands at most
//    ~1032:1: a header that claims more than the data can hold is not trusted with memory.
bool inflate(Scratch& scratch, std::size_t filtered_bytes) {
  if (filtered_bytes / 1032 > scratch.idat.size() + 64) return false;
  scratch.filtered.resize(filtered_bytes);
  return inflate_zlib(scratch.idat.data(), scratch.idat.size(), scratch.filtered.data(),
                      filtered_bytes);
}

// A Sub row unfiltered and converted into OpenCV's layout in one pass.
void sub_row(const unsigned char* src, unsigned char* dst, std::uint32_t width, int bit_depth,
             int channels) {
  if (bit_depth == 16)
    sub_row_16bit(src, reinterpret_cast<std::uint16_t*>(dst), width);
  else if (channels == 3)
    sub_row_8bit<3>(src, dst, width);
  else if (channels == 4)
    sub_row_8bit<4>(src, dst, width);
  else
    sub_row_8bit<1>(src, dst, width);
}

// An unfiltered row into OpenCV's layout: BGR(A), 16-bit values in host order.
void to_opencv_row(const unsigned char* src, unsigned char* dst, std::uint32_t width, int bit_depth,
                   int channels, std::size_t row_bytes) {
  if (bit_depth == 16) {
    auto* out = reinterpret_cast<std::uint16_t*>(dst);
    for (std::uint32_t x = 0; x < width; ++x)
      out[x] = static_cast<std::uint16_t>((src[2 * x] << 8) | src[2 * x + 1]);
  } else if (channels == 3) {
    for (std::uint32_t x = 0; x < width; ++x) {
      dst[3 * x] = src[3 * x + 2];
      dst[3 * x + 1] = src[3 * x + 1];
      dst[3 * x + 2] = src[3 * x];
    }
  } else if (channels == 4) {
    for (std::uint32_t x = 0; x < width; ++x) {
      dst[4 * x] = src[4 * x + 2];
      dst[4 * x + 1] = src[4 * x + 1];
      dst[4 * x + 2] = src[4 * x];
      dst[4 * x + 3] = src[4 * x + 3];
    }
  } else {
    std::memcpy(dst, src, row_bytes);
  }
}

// 4. Unfilter row by row (`filtered`: per row a filter byte and row_bytes bytes) into `image`.
//    False for an unknown filter.
bool unfilter_into(unsigned char* filtered, const Header& header, int channels,
                   std::size_t row_bytes, std::size_t bpp, cv::Mat& image) {
  const unsigned char* prev = nullptr;
  for (std::uint32_t y = 0; y < header.height; ++y) {
    unsigned char* row = filtered + std::size_t{y} * (row_bytes + 1);
    unsigned char* dst = image.ptr<unsigned char>(static_cast<int>(y));
    // A Sub row whose unfiltered bytes the next row does not need (it is not Up, Average or
    // Paeth): unfiltered and converted in one pass.
    const int next_filter = y + 1 < header.height ? row[row_bytes + 1] : 0;
    if (row[0] == 1 && next_filter != 2 && next_filter != 3 && next_filter != 4) {
      sub_row(row + 1, dst, header.width, header.bit_depth, channels);
      prev = nullptr;  // not needed: the next row does not look up
      continue;
    }
    if (!unfilter(row[0], row + 1, prev, row_bytes, bpp)) return false;
    prev = row + 1;
    to_opencv_row(row + 1, dst, header.width, header.bit_depth, channels, row_bytes);
  }
  return true;
}

}  // namespace

bool png_size(const unsigned char* data, std::size_t size, std::uint32_t& width,
              std::uint32_t& height) {
  if (size < 24 || std::memcmp(data, kSignature, 8) != 0 || std::memcmp(data + 12, "IHDR", 4) != 0)
    return false;
  width = be32(data + 16);
  height = be32(data + 20);
  return true;
}

cv::Mat decode_png_fast(const unsigned char* data, std::size_t size) {
  if (size < 8 + 25 || std::memcmp(data, kSignature, 8) != 0) return {};
  thread_local Scratch scratch;
  Header header;
  if (!read_chunks(data, size, header, scratch.idat)) return {};
  const int channels = channels_of(header);
  if (channels == 0) return {};
  const std::size_t bpp = static_cast<std::size_t>(channels) * (header.bit_depth / 8);
  const std::size_t row_bytes = std::size_t{header.width} * bpp;
  if (!inflate(scratch, std::size_t{header.height} * (row_bytes + 1))) return {};
  const int type = header.bit_depth == 16 ? CV_16UC1 : CV_MAKETYPE(CV_8U, channels);
  cv::Mat image(static_cast<int>(header.height), static_cast<int>(header.width), type);
  if (!unfilter_into(scratch.filtered.data(), header, channels, row_bytes, bpp, image)) return {};
  return image;
}

}  // namespace objmap::io
