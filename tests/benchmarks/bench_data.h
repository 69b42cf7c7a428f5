#pragma once
// Where the benchmarks find the real data: $OBJMAP_DATA, else <repo>/../shared/data (as the tests).
#include <cstdlib>
#include <filesystem>

namespace objmap::bench {

inline std::filesystem::path data_dir() {
  if (const char* env = std::getenv("OBJMAP_DATA")) return env;
  return std::filesystem::path(OBJMAP_SOURCE_DIR) / ".." / "shared" / "data";
}

}  // namespace objmap::bench
