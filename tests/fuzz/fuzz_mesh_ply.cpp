// PLY meshes (io/ply.h, read_mesh_ply): vertices with normals and colours, faces as index lists.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "objmap/io/ply.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const auto file = fuzz::write_file(fuzz::fresh_dir(), "mesh.ply", fuzz::whole(data, size));
  fuzz::accept_input_error([&] { io::read_mesh_ply(file); });
  return 0;
}
