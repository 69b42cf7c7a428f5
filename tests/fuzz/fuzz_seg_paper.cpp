// The paper's pixel lists (segmentation/read_txt.cpp, txt-paper): <ts>/<class>/<track_id>.txt with
// "u v" lines; two tracks of one frame, separated; read with a 64x48 image.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "objmap/segmentation/read.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const auto parts = fuzz::split(data, size, 2);
  const auto dir = fuzz::fresh_dir();
  fuzz::write_file(dir, "1.5/cup/3.txt", parts[0]);
  fuzz::write_file(dir, "1.5/tv/12.txt", parts[1]);
  segmentation::ReadOptions options;
  options.image_width = 64;
  options.image_height = 48;
  fuzz::accept_input_error([&] { segmentation::read_segmentation(dir, options); });
  return 0;
}
