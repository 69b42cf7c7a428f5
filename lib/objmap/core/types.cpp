#include "objmap/core/types.h"

namespace objmap {

bool Obb::contains(const Vec3& point_in_world, double margin) const {
  const Vec3 local = rotation.transpose() * (point_in_world - center);
  return (local.cwiseAbs().array() <= (half_extent.array() + margin)).all();
}

}  // namespace objmap
