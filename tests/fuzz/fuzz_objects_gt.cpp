// Ground-truth objects (eval/objects.h, read_objects_gt): objects_gt.json of objmap synth or
// cuboid lines "x y z yaw half_x half_y half_z", told apart by content; and the scene fields of
// objects_gt.json (io/scene_json.h, read_gt_scene), as `objmap eval scene` reads them.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "objmap/eval/objects.h"
#include "objmap/io/scene_json.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const auto file = fuzz::write_file(fuzz::fresh_dir(), "objects_gt", fuzz::whole(data, size));
  fuzz::accept_input_error([&] { eval::read_objects_gt(file); });
  fuzz::accept_input_error([&] { io::read_gt_scene(file); });
  return 0;
}
