// objmap's camera JSON (io/camera_io.h, read_camera_file on a .json).
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "objmap/io/camera_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const auto file = fuzz::write_file(fuzz::fresh_dir(), "camera.json", fuzz::whole(data, size));
  fuzz::accept_input_error([&] { io::read_camera_file(file); });
  return 0;
}
