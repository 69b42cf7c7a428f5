// The text files of the 7-Scenes, Open3D, Replica and ScanNet layouts (io/dataset.h,
// read_dataset): a 7-Scenes frame-000000.pose.txt, separator, an Open3D .log trajectory,
// separator, an Open3D intrinsic JSON, separator, a Replica cam_params.json, separator, a Replica
// traj.txt, separator, a ScanNet intrinsic_depth.txt. Each layout's folder holds one 8x6 frame.
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
  const std::string identity = "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
  const auto parts = fuzz::split(data, size, 6);
  const auto root = fuzz::fresh_dir();
  const fuzz::fs::path seven = root / "7scenes", open3d = root / "open3d",
                       replica = root / "replica" / "s", scannet = root / "scannet";
  fuzz::write_file(seven, "frame-000000.color.png", color);
  fuzz::write_file(seven, "frame-000000.depth.png", depth);
  fuzz::write_file(seven, "frame-000000.pose.txt", parts[0]);
  fuzz::write_file(open3d, "color/0.png", color);
  fuzz::write_file(open3d, "depth/0.png", depth);
  fuzz::write_file(open3d, "scene/trajectory.log", parts[1]);
  fuzz::write_file(open3d, "intrinsic.json", parts[2]);
  fuzz::write_file(replica.parent_path(), "cam_params.json", parts[3]);
  fuzz::write_file(replica, "results/frame000000.png", color);
  fuzz::write_file(replica, "results/depth000000.png", depth);
  fuzz::write_file(replica, "traj.txt", parts[4]);
  fuzz::write_file(scannet, "color/0.png", color);
  fuzz::write_file(scannet, "depth/0.png", depth);
  fuzz::write_file(scannet, "pose/0.txt", identity);
  fuzz::write_file(scannet, "intrinsic/intrinsic_color.txt",
                   "4 0 3.5 0\n0 4 2.5 0\n0 0 1 0\n0 0 0 1\n");
  fuzz::write_file(scannet, "intrinsic/intrinsic_depth.txt", parts[5]);
  for (const fuzz::fs::path& dir : {seven, open3d, replica, scannet})
    fuzz::accept_input_error([&] {
      const io::Dataset d = io::read_dataset(dir);
      if (!d.frames.empty()) io::read_frame_depth(d, d.frames.front(), *d.camera);
    });
  return 0;
}
