// Canonical segmentation JSON (segmentation/read.h): a folder with one <timestamp>.json frame
// (instances with COCO RLE masks, boxes, classes, scores), format detected; read with any image
// size and with a required 8x6 image.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "objmap/segmentation/read.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const auto dir = fuzz::fresh_dir();
  fuzz::write_file(dir, "1.5.json", fuzz::whole(data, size));
  segmentation::ReadOptions sized;
  sized.image_width = 8;
  sized.image_height = 6;
  fuzz::accept_input_error([&] { segmentation::read_segmentation(dir); });
  fuzz::accept_input_error([&] { segmentation::read_segmentation(dir, sized); });
  return 0;
}
