#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "objmap/geometry/pixel_runs.h"

// objmap follow's kept pixels, compressed: a keyframe's observations are kept as pixel runs for a
// loop closure (geometry/pixel_runs.h: 5 bytes a point), which is the part of follow's memory that
// grows with the recording. Packed, the runs' depths and colours are each point's difference from
// the point before, as byte planes (the depths' low bytes, their high bytes, then red, green and
// blue), deflated: ~2-2.5 bytes a point on real and synthetic recordings (docs/follow.md,
// "Memory"). Unpacked, they are the runs they were made of, bit for bit.
namespace objmap::pipeline {

struct PackedPixelRuns {
  int stride = 1;
  std::vector<std::uint32_t> first, end;  // as PixelRuns'
  std::size_t points = 0;
  bool colors = false;
  std::vector<std::uint8_t> planes;  // deflated

  std::size_t bytes() const;  // what they hold
};

// `runs` packed; their run starts and ends are moved, not copied.
PackedPixelRuns pack_pixel_runs(geometry::PixelRuns runs);

// The runs `packed` was made of. Throws std::logic_error when its planes do not inflate to its
// points (memory corrupted: it is never read from a file).
geometry::PixelRuns unpack_pixel_runs(const PackedPixelRuns& packed);

}  // namespace objmap::pipeline
