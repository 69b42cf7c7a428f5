#include "objmap/pipeline/packed_pixels.h"

#include <stdexcept>
#include <utility>

#include "objmap/io/deflate.h"

namespace objmap::pipeline {

std::size_t PackedPixelRuns::bytes() const {
  return (first.size() + end.size()) * sizeof(std::uint32_t) + planes.size();
}

PackedPixelRuns pack_pixel_runs(geometry::PixelRuns runs) {
  PackedPixelRuns p;
  p.stride = runs.stride;
  p.first = std::move(runs.first);
  p.end = std::move(runs.end);
  p.points = runs.size();
  p.colors = !runs.colors.empty();
  const std::size_t n = p.points;
  std::vector<std::uint8_t> planes(n * (p.colors ? 5 : 2));
  std::uint16_t last_raw = 0;
  Rgb last{0, 0, 0};
  for (std::size_t i = 0; i < n; ++i) {
    const auto d = static_cast<std::uint16_t>(runs.raw[i] - last_raw);
    last_raw = runs.raw[i];
    planes[i] = static_cast<std::uint8_t>(d & 0xff);
    planes[n + i] = static_cast<std::uint8_t>(d >> 8);
    if (!p.colors) continue;
    const Rgb c = runs.colors[i];
    planes[2 * n + i] = static_cast<std::uint8_t>(c.r - last.r);
    planes[3 * n + i] = static_cast<std::uint8_t>(c.g - last.g);
    planes[4 * n + i] = static_cast<std::uint8_t>(c.b - last.b);
    last = c;
  }
  p.planes = io::deflate_bytes(planes.data(), planes.size());
  return p;
}

geometry::PixelRuns unpack_pixel_runs(const PackedPixelRuns& packed) {
  const std::size_t n = packed.points;
  std::vector<std::uint8_t> planes(n * (packed.colors ? 5 : 2));
  if (!io::inflate_bytes(packed.planes, planes.data(), planes.size()))
    throw std::logic_error("unpack_pixel_runs: the packed planes do not inflate to " +
                           std::to_string(n) + " points");
  geometry::PixelRuns runs;
  runs.stride = packed.stride;
  runs.first = packed.first;
  runs.end = packed.end;
  runs.raw.resize(n);
  if (packed.colors) runs.colors.resize(n);
  std::uint16_t raw = 0;
  Rgb c{0, 0, 0};
  for (std::size_t i = 0; i < n; ++i) {
    raw = static_cast<std::uint16_t>(raw + (planes[i] | planes[n + i] << 8));
    runs.raw[i] = raw;
    if (!packed.colors) continue;
    c = Rgb{static_cast<std::uint8_t>(c.r + planes[2 * n + i]),
            static_cast<std::uint8_t>(c.g + planes[3 * n + i]),
            static_cast<std::uint8_t>(c.b + planes[4 * n + i])};
    runs.colors[i] = c;
  }
  return runs;
}

}  // namespace objmap::pipeline
