// A run folder as `objmap summary` reads it (io/run_summary.h): map/objects.json, separator,
// map/run.json, separator, stages.json, separator, benchmarks/fuse.tsv, separator,
// benchmarks/fuse.time, separator, eval/ate.json, separator, eval/objects.json, separator,
// logs/fuse.log. Someone else's run folder is outside data.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "objmap/io/run_summary.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace objmap;
  const auto parts = fuzz::split(data, size, 8);
  const auto run = fuzz::fresh_dir() / "run";
  const char* const names[] = {"map/objects.json",    "map/run.json",         "stages.json",
                               "benchmarks/fuse.tsv", "benchmarks/fuse.time", "eval/ate.json",
                               "eval/objects.json",   "logs/fuse.log"};
  for (std::size_t i = 0; i < 8; ++i)
    if (!parts[i].empty()) fuzz::write_file(run, names[i], parts[i]);
  fuzz::accept_input_error([&] { io::read_run_summary(run); });
  return 0;
}
