#pragma once
#include <cstdint>
#include <string>

// FNV-1a 64: the checksums of inputs in run.json and the keys of `objmap run`'s stages.
namespace objmap {

constexpr std::uint64_t kFnv1aOffset = 1469598103934665603ULL;

// FNV-1a 64 of `bytes`, continuing from `h` (the offset basis for a fresh hash).
std::uint64_t fnv1a(const std::string& bytes, std::uint64_t h = kFnv1aOffset);

// `h` as 16 lower-case hex digits.
std::string hex64(std::uint64_t h);

}  // namespace objmap
