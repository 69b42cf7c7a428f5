// A TUM RGB-D folder's lists (io/tum_dataset.h, read_tum_dataset): rgb.txt, separator, depth.txt.
// The images rgb/1.png and depth/1.png exist (empty: the lists are what is read here).
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "objmap/io/tum_dataset.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const auto parts = fuzz::split(data, size, 2);
  const auto dir = fuzz::fresh_dir();
  fuzz::write_file(dir, "rgb.txt", parts[0]);
  fuzz::write_file(dir, "depth.txt", parts[1]);
  fuzz::write_file(dir, "rgb/1.png", "");
  fuzz::write_file(dir, "depth/1.png", "");
  fuzz::accept_input_error([&] { io::read_tum_dataset(dir); });
  return 0;
}
