// A class sizes file (`fuse --class-sizes FILE`, segmentation/class_sizes.h).
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "objmap/segmentation/class_sizes.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const auto file = fuzz::write_file(fuzz::fresh_dir(), "sizes.json", fuzz::whole(data, size));
  fuzz::accept_input_error([&] {
    const segmentation::ClassSizes sizes = segmentation::ClassSizes::from_spec(file.string());
    (void)sizes.find("chair");
  });
  return 0;
}
