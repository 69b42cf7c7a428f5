// The image files of a recording (io/image.h): the same bytes read as a colour image, as a depth
// image (any size, and required to be 64x48) and as any image, from a file.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "objmap/io/image.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const auto file = fuzz::write_file(fuzz::fresh_dir(), "frame.png", fuzz::whole(data, size));
  fuzz::accept_input_error([&] { io::read_rgb(file, 0, 0); });
  fuzz::accept_input_error([&] { io::read_depth(file, 0, 0); });
  fuzz::accept_input_error([&] { io::read_depth(file, 64, 48); });
  fuzz::accept_input_error([&] { io::read_image(file, /*allow_jpeg=*/true); });
  return 0;
}
