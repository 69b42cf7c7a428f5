// PNG label images (segmentation/read_png.cpp): <ts>.png, separator, the folder's classes.txt,
// separator, the sidecar <ts>.instances.json (each written when not empty), format "png".
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "objmap/segmentation/read.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const auto parts = fuzz::split(data, size, 3);
  const auto dir = fuzz::fresh_dir();
  fuzz::write_file(dir, "1.5.png", parts[0]);
  if (!parts[1].empty()) fuzz::write_file(dir, "classes.txt", parts[1]);
  if (!parts[2].empty()) fuzz::write_file(dir, "1.5.instances.json", parts[2]);
  segmentation::ReadOptions options;
  options.format = "png";
  fuzz::accept_input_error([&] { segmentation::read_segmentation(dir, options); });
  return 0;
}
