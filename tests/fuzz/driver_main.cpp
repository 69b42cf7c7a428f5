// The plain-program form of a fuzz target, built by the normal build (without libFuzzer): runs
// LLVMFuzzerTestOneInput once on each seed file, so that `make test` builds every target and runs
// it over its seeds. Usage: fuzz_<name> PATH...; a PATH is a file, a folder (its files,
// recursively, in name order) or data:<relative>, a file or folder of the real data ($OBJMAP_DATA,
// else
// ../shared/data beside the repository; missing: skipped, or a failure with OBJMAP_REQUIRE_DATA=1).
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace fs = std::filesystem;

namespace {

fs::path data_dir() {
  if (const char* env = std::getenv("OBJMAP_DATA"); env && *env) return env;
  return fs::path(OBJMAP_SOURCE_DIR) / ".." / "shared" / "data";
}

bool data_required() {
  const char* env = std::getenv("OBJMAP_REQUIRE_DATA");
  return env && std::string(env) == "1";
}

// The seed files of `arg`, in name order; false when a data: path is missing.
bool seed_files(const std::string& arg, std::vector<fs::path>& files) {
  const std::string prefix = "data:";
  const fs::path path =
      arg.rfind(prefix, 0) == 0 ? data_dir() / arg.substr(prefix.size()) : fs::path(arg);
  if (!fs::exists(path)) return false;
  if (!fs::is_directory(path)) {
    files.push_back(path);
    return true;
  }
  std::vector<fs::path> found;
  for (const auto& entry : fs::recursive_directory_iterator(path))
    if (entry.is_regular_file()) found.push_back(entry.path());
  std::sort(found.begin(), found.end());
  files.insert(files.end(), found.begin(), found.end());
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<fs::path> files;
  int missing = 0;
  for (int i = 1; i < argc; ++i) {
    if (seed_files(argv[i], files)) continue;
    std::printf("%s: missing seed %s (set OBJMAP_DATA to the real data folder)\n", argv[0],
                argv[i]);
    ++missing;
  }
  for (const fs::path& file : files) {
    std::printf("%s\n", file.string().c_str());
    std::fflush(stdout);  // names the input if it crashes
    std::ifstream in(file, std::ios::binary);
    const std::vector<char> bytes{std::istreambuf_iterator<char>(in), {}};
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
  }
  std::printf("%s: %zu inputs, no finding\n", argv[0], files.size());
  if (files.empty() || (missing > 0 && data_required())) return 1;
  return 0;
}
