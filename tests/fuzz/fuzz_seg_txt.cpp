// Box files (segmentation/read_txt.cpp): two frames <ts>.txt (the first line of the first decides
// the layout: boxes-named, boxes-coco or boxes-xywh), format detected; read with any image size
// and with a required 640x480 image.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "objmap/segmentation/read.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const auto parts = fuzz::split(data, size, 2);
  const auto dir = fuzz::fresh_dir();
  fuzz::write_file(dir, "1.5.txt", parts[0]);
  fuzz::write_file(dir, "2.5.txt", parts[1]);
  segmentation::ReadOptions sized;
  sized.image_width = 640;
  sized.image_height = 480;
  fuzz::accept_input_error([&] { segmentation::read_segmentation(dir); });
  fuzz::accept_input_error([&] { segmentation::read_segmentation(dir, sized); });
  return 0;
}
