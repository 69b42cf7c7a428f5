// The "points" block of RUN/run.json (eval/objects.h, read_point_counts; Table 6).
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "objmap/eval/objects.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const auto file = fuzz::write_file(fuzz::fresh_dir(), "run.json", fuzz::whole(data, size));
  fuzz::accept_input_error([&] { eval::read_point_counts(file).reduction(); });
  return 0;
}
