#pragma once
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "objmap/core/error.h"

// What the fuzz targets of this folder share (docs/testing.md). A target is
//   extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
// that hands the bytes to one reader of outside data. The reader's answer to bad input is an
// InputError whose message is one non-empty line; anything else (another exception, a message of
// several lines, a crash, a sanitizer report, a hang) is a finding.
namespace objmap::fuzz {

namespace fs = std::filesystem;

// The files of a multi-file input (a segmentation folder, rgb.txt + depth.txt) are separated by
// this line.
inline constexpr std::string_view kSeparator = "\n--8<--\n";

// The input cut at each kSeparator into at most `parts` pieces (the last one keeps any further
// separators); missing pieces are empty.
std::vector<std::string_view> split(const std::uint8_t* data, std::size_t size, std::size_t parts);

// The input as one piece.
std::string_view whole(const std::uint8_t* data, std::size_t size);

// An empty scratch folder of this process (emptied at each call; removed at exit).
fs::path fresh_dir();

// Writes `bytes` to dir / name, creating the folders of `name`; returns the path.
fs::path write_file(const fs::path& dir, const std::string& name, std::string_view bytes);

// True above 2^22 pixels: a valid image that only takes long to decode (a few dozen bytes of JPEG
// can claim 2^30). The image targets skip such headers where no size is required, to try more
// inputs; io/image.h refuses them by size before decoding when the camera's size is given.
inline bool too_many_pixels(std::uint32_t width, std::uint32_t height) {
  return std::uint64_t{width} * height > (std::uint64_t{1} << 22);
}

// Aborts with `what` on stderr: a finding that is not a crash of its own (a wrong result).
[[noreturn]] void finding(const std::string& what);

// Checks that an InputError's message is one non-empty line (else a finding); prints it when
// OBJMAP_FUZZ_VERBOSE=1 (to see how far a seed gets).
void check_message(const InputError& error);

// Runs `read`, accepting an InputError of one non-empty line.
template <typename Read>
void accept_input_error(Read&& read) {
  try {
    read();
  } catch (const InputError& e) {
    check_message(e);
  }
}

}  // namespace objmap::fuzz
