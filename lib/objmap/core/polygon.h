#pragma once
#include <vector>

#include "objmap/core/types.h"

namespace objmap {

// True when `point`, moved along `direction`, can fall inside the convex polygon `corners` (given
// in cyclic order, either sense): "over a surface" when `direction` is up. A polygon of fewer than
// 3 corners contains nothing.
bool projects_into_polygon(const Vec3& point, const std::vector<Vec3>& corners,
                           const Vec3& direction);

}  // namespace objmap
