#include "objmap/io/png_encode.h"

#include <cstring>
#include <string>

#include <zlib.h>

#include "objmap/core/error.h"

namespace objmap::io {

namespace {

void put32(std::vector<std::uint8_t>* out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8)
    out->push_back(static_cast<std::uint8_t>(v >> shift));
}

// Appends a chunk: length, type, data, CRC of type and data.
void put_chunk(std::vector<std::uint8_t>* out, const char* type, const std::uint8_t* data,
               std::size_t size) {
  put32(out, static_cast<std::uint32_t>(size));
  const std::size_t start = out->size();
  out->insert(out->end(), type, type + 4);
  if (size > 0) out->insert(out->end(), data, data + size);
  const uLong crc = crc32(crc32(0L, Z_NULL, 0), out->data() + start, static_cast<uInt>(size + 4));
  put32(out, static_cast<std::uint32_t>(crc));
}

}  // namespace

void encode_png(const cv::Mat& image, std::vector<std::uint8_t>* png) {
  int channels = 0, bytes_per_sample = 0, colour_type = 0;
  switch (image.type()) {
    case CV_8UC3:
      channels = 3, bytes_per_sample = 1, colour_type = 2;
      break;
    case CV_8UC1:
      channels = 1, bytes_per_sample = 1, colour_type = 0;
      break;
    case CV_16UC1:
      channels = 1, bytes_per_sample = 2, colour_type = 0;
      break;
    default:
      throw InputError("encode_png", "image type " + std::to_string(image.type()) +
                                         "; expected CV_8UC3, CV_8UC1 or CV_16UC1");
  }
  require(image.cols > 0 && image.rows > 0, "encode_png", "empty image");
  const int bpp = channels * bytes_per_sample;  // bytes per pixel (filter distance)
  const std::size_t row_bytes = static_cast<std::size_t>(image.cols) * bpp;

  // Raw scanlines in PNG byte order (RGB, big-endian), each after its filter byte (1 = Sub:
  // difference to the byte one pixel to the left).
  thread_local std::vector<std::uint8_t> filtered, raw;  // reused: no page faults per image
  filtered.resize((row_bytes + 1) * image.rows);
  raw.resize(row_bytes);
  for (int v = 0; v < image.rows; ++v) {
    const std::uint8_t* in = image.ptr<std::uint8_t>(v);
    if (image.type() == CV_8UC3) {
      for (int u = 0; u < image.cols; ++u) {
        raw[3 * u] = in[3 * u + 2];
        raw[3 * u + 1] = in[3 * u + 1];
        raw[3 * u + 2] = in[3 * u];
      }
    } else if (image.type() == CV_16UC1) {
      const auto* in16 = image.ptr<std::uint16_t>(v);
      for (int u = 0; u < image.cols; ++u) {
        raw[2 * u] = static_cast<std::uint8_t>(in16[u] >> 8);
        raw[2 * u + 1] = static_cast<std::uint8_t>(in16[u] & 0xFF);
      }
    } else {
      std::memcpy(raw.data(), in, row_bytes);
    }
    std::uint8_t* out = filtered.data() + static_cast<std::size_t>(v) * (row_bytes + 1);
    out[0] = 1;  // Sub
    for (int k = 0; k < bpp; ++k) out[1 + k] = raw[k];
    for (std::size_t k = bpp; k < row_bytes; ++k)
      out[1 + k] = static_cast<std::uint8_t>(raw[k] - raw[k - bpp]);
  }

  // signature, IHDR, then IDAT compressed straight into `png`, IEND.
  png->clear();
  const std::uint8_t signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  png->insert(png->end(), signature, signature + 8);
  std::vector<std::uint8_t> header;
  put32(&header, static_cast<std::uint32_t>(image.cols));
  put32(&header, static_cast<std::uint32_t>(image.rows));
  header.push_back(static_cast<std::uint8_t>(8 * bytes_per_sample));  // bit depth
  header.push_back(static_cast<std::uint8_t>(colour_type));
  header.push_back(0);  // deflate
  header.push_back(0);  // adaptive filtering (per-row filter bytes)
  header.push_back(0);  // no interlace
  put_chunk(png, "IHDR", header.data(), header.size());

  z_stream z{};
  require(deflateInit2(&z, 1, Z_DEFLATED, 15, 8, Z_RLE) == Z_OK, "encode_png",
          "zlib initialisation failed");
  const std::size_t idat = png->size();  // where the IDAT length goes
  const std::size_t bound = deflateBound(&z, static_cast<uLong>(filtered.size()));
  png->resize(idat + 8 + bound);
  std::memcpy(png->data() + idat + 4, "IDAT", 4);
  z.next_in = filtered.data();
  z.avail_in = static_cast<uInt>(filtered.size());
  z.next_out = png->data() + idat + 8;
  z.avail_out = static_cast<uInt>(bound);
  const int status = deflate(&z, Z_FINISH);
  const std::size_t compressed_size = bound - z.avail_out;
  deflateEnd(&z);
  require(status == Z_STREAM_END, "encode_png", "zlib compression failed");
  png->resize(idat + 8 + compressed_size);
  std::vector<std::uint8_t> length;
  put32(&length, static_cast<std::uint32_t>(compressed_size));
  std::memcpy(png->data() + idat, length.data(), 4);
  const uLong crc =
      crc32(crc32(0L, Z_NULL, 0), png->data() + idat + 4, static_cast<uInt>(compressed_size + 4));
  put32(png, static_cast<std::uint32_t>(crc));
  put_chunk(png, "IEND", nullptr, 0);
}

}  // namespace objmap::io
