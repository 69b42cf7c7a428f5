#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

// Raw DEFLATE (RFC 1951) of bytes held in memory, through libdeflate: what objmap keeps
// compressed while it runs (objmap follow's kept pixels), not a file format.
namespace objmap::io {

// `size` bytes at `data` deflated at libdeflate's level 1 (its fastest, ~150 MB/s here).
std::vector<std::uint8_t> deflate_bytes(const std::uint8_t* data, std::size_t size);

// Inflates `packed` into exactly `size` bytes at `out`; false when `packed` is not a raw DEFLATE
// stream of exactly that many bytes.
bool inflate_bytes(const std::vector<std::uint8_t>& packed, std::uint8_t* out, std::size_t size);

}  // namespace objmap::io
