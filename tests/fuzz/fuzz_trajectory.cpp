// TUM trajectories (io/trajectory.h, read_trajectory), and a pose looked up in what was read.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "objmap/io/trajectory.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const auto file = fuzz::write_file(fuzz::fresh_dir(), "traj.txt", fuzz::whole(data, size));
  fuzz::accept_input_error([&] {
    const Trajectory trajectory = io::read_trajectory(file);
    io::PoseLookupOptions options;
    options.interpolate = true;
    const double middle =
        (trajectory.poses.front().timestamp + trajectory.poses.back().timestamp) / 2;
    io::lookup_pose(trajectory, middle, options);
  });
  return 0;
}
