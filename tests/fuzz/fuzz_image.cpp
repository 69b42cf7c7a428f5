// The image files of a recording (io/image.h): the same bytes read as a colour and as a depth image
// of the camera's size (64x48), then, when the header claims no huge image, of any size and as any
// image, from a file.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "objmap/io/codecs.h"
#include "objmap/io/image.h"
#include "objmap/io/png_fast.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const auto file = fuzz::write_file(fuzz::fresh_dir(), "frame.png", fuzz::whole(data, size));
  fuzz::accept_input_error([&] { io::read_rgb(file, 64, 48); });
  fuzz::accept_input_error([&] { io::read_depth(file, 64, 48); });
  std::uint32_t width = 0, height = 0;
  if ((io::png_size(data, size, width, height) || io::jpeg_size(data, size, width, height)) &&
      fuzz::too_many_pixels(width, height))
    return 0;
  fuzz::accept_input_error([&] { io::read_rgb(file, 0, 0); });
  fuzz::accept_input_error([&] { io::read_depth(file, 0, 0); });
  fuzz::accept_input_error([&] { io::read_image(file, /*allow_jpeg=*/true); });
  return 0;
}
