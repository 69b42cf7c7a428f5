#include "fuzz_util.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <system_error>

namespace objmap::fuzz {

std::vector<std::string_view> split(const std::uint8_t* data, std::size_t size, std::size_t parts) {
  std::string_view rest = whole(data, size);
  std::vector<std::string_view> pieces;
  while (pieces.size() + 1 < parts) {
    const std::size_t at = rest.find(kSeparator);
    if (at == std::string_view::npos) break;
    pieces.push_back(rest.substr(0, at));
    rest.remove_prefix(at + kSeparator.size());
  }
  pieces.push_back(rest);
  pieces.resize(parts);
  return pieces;
}

std::string_view whole(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

namespace {

void remove_scratch();

// Never freed: the exit handler that removes it runs after the destructors of static objects.
const fs::path& scratch_root() {
  static const fs::path* const root = [] {
    auto* dir =
        new fs::path(fs::temp_directory_path() / ("objmap-fuzz-" + std::to_string(getpid())));
    std::atexit(remove_scratch);
    return dir;
  }();
  return *root;
}

void remove_scratch() {
  std::error_code ec;
  fs::remove_all(scratch_root(), ec);
}

}  // namespace

fs::path fresh_dir() {
  const fs::path dir = scratch_root();
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

fs::path write_file(const fs::path& dir, const std::string& name, std::string_view bytes) {
  const fs::path path = dir / name;
  fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) finding("cannot write the scratch file " + path.string());
  return path;
}

void check_message(const InputError& error) {
  static const bool verbose = [] {
    const char* env = std::getenv("OBJMAP_FUZZ_VERBOSE");
    return env && std::string(env) == "1";
  }();
  const std::string message = error.what();
  if (message.empty() || message.find('\n') != std::string::npos)
    finding("InputError message is not one non-empty line: '" + message + "'");
  if (verbose) std::fprintf(stderr, "InputError: %s\n", message.c_str());
}

void finding(const std::string& what) {
  std::fprintf(stderr, "FUZZ FINDING: %s\n", what.c_str());
  std::abort();
}

}  // namespace objmap::fuzz
