#include "objmap/io/deflate.h"

#include <libdeflate.h>

#include <memory>
#include <new>

namespace objmap::io {
namespace {

struct CompressorDeleter {
  void operator()(libdeflate_compressor* c) const { libdeflate_free_compressor(c); }
};
struct DecompressorDeleter {
  void operator()(libdeflate_decompressor* d) const { libdeflate_free_decompressor(d); }
};

// One of each per thread, made at its first use and kept (a compressor holds ~100 kB of tables).
libdeflate_compressor* compressor() {
  thread_local std::unique_ptr<libdeflate_compressor, CompressorDeleter> c{
      libdeflate_alloc_compressor(1)};
  if (!c) throw std::bad_alloc();
  return c.get();
}

libdeflate_decompressor* decompressor() {
  thread_local std::unique_ptr<libdeflate_decompressor, DecompressorDeleter> d{
      libdeflate_alloc_decompressor()};
  if (!d) throw std::bad_alloc();
  return d.get();
}

}  // namespace

std::vector<std::uint8_t> deflate_bytes(const std::uint8_t* data, std::size_t size) {
  libdeflate_compressor* c = compressor();
  std::vector<std::uint8_t> out(libdeflate_deflate_compress_bound(c, size));
  const std::size_t n = libdeflate_deflate_compress(c, data, size, out.data(), out.size());
  out.resize(n);  // never 0 with a buffer of the bound's size
  out.shrink_to_fit();
  return out;
}

bool inflate_bytes(const std::vector<std::uint8_t>& packed, std::uint8_t* out, std::size_t size) {
  std::size_t written = 0;
  return libdeflate_deflate_decompress(decompressor(), packed.data(), packed.size(), out, size,
                                       &written) == LIBDEFLATE_SUCCESS &&
         written == size;
}

bool inflate_zlib(const std::uint8_t* packed, std::size_t packed_size, std::uint8_t* out,
                  std::size_t size) {
  std::size_t written = 0;
  return libdeflate_zlib_decompress(decompressor(), packed, packed_size, out, size, &written) ==
             LIBDEFLATE_SUCCESS &&
         written == size;
}

}  // namespace objmap::io
