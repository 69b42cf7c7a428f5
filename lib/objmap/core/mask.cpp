#include "objmap/core/mask.h"

#include <algorithm>

namespace objmap {

std::size_t Mask::area() const {
  return static_cast<std::size_t>(
      std::count_if(data.begin(), data.end(), [](std::uint8_t v) { return v != 0; }));
}

}  // namespace objmap
