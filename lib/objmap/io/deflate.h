#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

// DEFLATE (RFC 1951) of bytes held in memory, through libdeflate, with one compressor and one
// decompressor per thread, made at its first use and kept: raw streams for what objmap keeps
// compressed while it runs (objmap follow's kept pixels), zlib streams (RFC 1950) for the PNG
// reader (png_fast.h).
namespace objmap::io {

// `size` bytes at `data` deflated at libdeflate's level 1 (its fastest, ~150 MB/s here).
std::vector<std::uint8_t> deflate_bytes(const std::uint8_t* data, std::size_t size);

// Inflates `packed` into exactly `size` bytes at `out`; false when `packed` is not a raw DEFLATE
// stream of exactly that many bytes.
bool inflate_bytes(const std::vector<std::uint8_t>& packed, std::uint8_t* out, std::size_t size);

// Inflates the zlib stream of `packed_size` bytes at `packed` (its Adler-32 checked) into exactly
// `size` bytes at `out`; false when it is not a zlib stream of exactly that many bytes.
bool inflate_zlib(const std::uint8_t* packed, std::size_t packed_size, std::uint8_t* out,
                  std::size_t size);

}  // namespace objmap::io
