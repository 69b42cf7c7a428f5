// PLY point clouds (io/ply.h, read_ply): binary little-endian and ASCII.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "objmap/io/ply.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const auto file = fuzz::write_file(fuzz::fresh_dir(), "cloud.ply", fuzz::whole(data, size));
  fuzz::accept_input_error([&] { io::read_ply(file); });
  return 0;
}
