// PLY point clouds (io/ply.h, read_ply, read_ply_blocks, ply_vertex_count): binary little-endian
// and ASCII; the blocks must add up to the whole read's points.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "fuzz_util.h"
#include "objmap/io/ply.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const auto file = fuzz::write_file(fuzz::fresh_dir(), "cloud.ply", fuzz::whole(data, size));
  fuzz::accept_input_error([&] {
    const PointCloud whole = io::read_ply(file);
    std::size_t points = 0;
    io::read_ply_blocks(file, [&](const PointCloud& block) {
      // Bit for bit (a fuzzed coordinate may be NaN).
      if (points + block.size() > whole.size() ||
          std::memcmp(block.points.data(), whole.points.data() + points,
                      block.size() * sizeof(Vec3f)) != 0)
        __builtin_trap();
      points += block.size();
    });
    if (points != whole.size() || io::ply_vertex_count(file) != whole.size()) __builtin_trap();
  });
  return 0;
}
