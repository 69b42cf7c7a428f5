// DIFF/diff.json as `objmap query --diff` and `objmap report --diff` read it (io/diff_json.h): a
// diff folder may come from another machine, another objmap or a hand edit.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "objmap/io/diff_json.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const auto file = fuzz::write_file(fuzz::fresh_dir(), "diff.json", fuzz::whole(data, size));
  fuzz::accept_input_error([&] { io::read_diff_json(file); });
  return 0;
}
