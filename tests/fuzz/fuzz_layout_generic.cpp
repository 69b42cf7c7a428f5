// The generic layout (io/dataset.h, read_dataset on a folder with objmap_layout.json):
// objmap_layout.json, separator, poses.txt, separator, K.txt. The folder holds two 8x6 frames,
// frame-000000.color.png / .depth.png and frame-000001.*, and a TUM trajectory traj.txt.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_util.h"
#include "objmap/io/dataset.h"
#include "tiny_frame.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const std::string& color = fuzz::tiny_color_png();
  const std::string& depth = fuzz::tiny_depth_png();
  const auto parts = fuzz::split(data, size, 3);
  const auto dir = fuzz::fresh_dir();
  fuzz::write_file(dir, "objmap_layout.json", parts[0]);
  fuzz::write_file(dir, "poses.txt", parts[1]);
  fuzz::write_file(dir, "K.txt", parts[2]);
  for (const char* n : {"frame-000000", "frame-000001"}) {
    fuzz::write_file(dir, std::string(n) + ".color.png", color);
    fuzz::write_file(dir, std::string(n) + ".depth.png", depth);
  }
  fuzz::write_file(dir, "traj.txt", "0 0 0 0 0 0 0 1\n0.0333 0 0 0 0 0 0 1\n");
  fuzz::accept_input_error([&] { io::read_dataset(dir); });
  return 0;
}
