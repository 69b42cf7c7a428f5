#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace objmap {

// Binary mask, row-major, one byte per pixel (0 or 1): an instance's pixels (segmentation/) that
// geometry/ back-projects.
struct Mask {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> data;

  bool empty() const { return data.empty(); }
  std::uint8_t at(int u, int v) const { return data[static_cast<std::size_t>(v) * width + u]; }
  std::size_t area() const;
};

}  // namespace objmap
