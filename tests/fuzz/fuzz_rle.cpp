// COCO compressed RLE strings (segmentation/rle.h) in memory: byte 0 is the height, byte 1 the
// width, the rest the counts string. A mask that decodes must encode back to the same runs.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_util.h"
#include "objmap/segmentation/rle.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  if (size < 2) return 0;
  const int height = data[0], width = data[1];
  const std::string counts(fuzz::whole(data + 2, size - 2));
  fuzz::accept_input_error([&] { segmentation::rle_counts_from_string(counts); });
  fuzz::accept_input_error([&] {
    const segmentation::Mask mask = segmentation::rle_decode(counts, height, width);
    const segmentation::Mask again =
        segmentation::rle_decode(segmentation::rle_encode(mask), height, width);
    if (again.data != mask.data) fuzz::finding("rle_decode(rle_encode(mask)) != mask");
  });
  return 0;
}
