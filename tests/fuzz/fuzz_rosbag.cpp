// The rosbag layout (io/rosbag.h): the input is a ROS 1 bag, read as `objmap fuse --dataset X.bag`
// reads it (the streams chosen, camera_info, transforms), then the first frame's colour and depth
// decoded. rosbag_storage's own exceptions must come out as one InputError naming the bag.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "objmap/io/dataset.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const auto bag = fuzz::write_file(fuzz::fresh_dir(), "input.bag", fuzz::whole(data, size));
  io::DatasetOptions options;
  options.layout = "rosbag";
  fuzz::accept_input_error([&] {
    const io::Dataset d = io::read_dataset(bag, options);
    if (d.frames.empty()) return;
    io::read_frame_rgb(d, d.frames.front(), 0, 0);
    if (d.camera) io::read_frame_depth(d, d.frames.front(), *d.camera);
  });
  return 0;
}
