// RUN/objects.json (io/objects_json.h, read_objects_json); a map that reads is then evaluated
// against itself as the reference (eval/objects.h), as `objmap eval objects --reference` does. Its
// scene fields (io/scene_json.h, read_map_scene), as `objmap query`, `report` and `eval scene` read
// them.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "objmap/eval/objects.h"
#include "objmap/io/objects_json.h"
#include "objmap/io/scene_json.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const auto file = fuzz::write_file(fuzz::fresh_dir(), "objects.json", fuzz::whole(data, size));
  fuzz::accept_input_error([&] {
    const auto objects = io::read_objects_json(file);
    eval::ObjectEvalReport report;
    report.mode = "reference";
    report.result = eval::evaluate_objects(objects, eval::to_reference(objects), report.options);
    eval::objects_eval_json(report);
  });
  fuzz::accept_input_error([&] { io::read_map_scene(file); });
  return 0;
}
