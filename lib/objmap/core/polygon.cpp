#include "objmap/core/polygon.h"

namespace objmap {

bool projects_into_polygon(const Vec3& point, const std::vector<Vec3>& corners,
                           const Vec3& direction) {
  if (corners.size() < 3) return false;
  double sign = 0.0;  // the sense of the corners, from the first edge the point is not on
  for (std::size_t k = 0; k < corners.size(); ++k) {
    const Vec3& a = corners[k];
    const Vec3& b = corners[(k + 1) % corners.size()];
    const double side = direction.dot((b - a).cross(point - a));
    if (side * sign < 0.0) return false;
    if (side != 0.0) sign = side;
  }
  return true;
}

}  // namespace objmap
