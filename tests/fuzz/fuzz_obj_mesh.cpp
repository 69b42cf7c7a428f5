// OBJ models and their poses (io/obj_mesh.h: read_obj_mesh, read_model_poses), as objmap eval
// surface reads them.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "objmap/io/obj_mesh.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const auto dir = fuzz::fresh_dir();
  const auto file = fuzz::write_file(dir, "model.obj", fuzz::whole(data, size));
  fuzz::accept_input_error([&] { io::read_obj_mesh(file); });
  fuzz::accept_input_error([&] { io::read_model_poses(file); });
  return 0;
}
