#pragma once
// Scenes for the object map's tests: box surfaces at voxel centres and observations of them.
#include <optional>
#include <string>
#include <utility>

#include "objmap/core/types.h"
#include "objmap/fusion/object_map.h"

namespace objmap::fusion::test {

// Surface points of an axis-aligned box at 1 cm voxel centres: `center` must be a voxel centre
// (x.xx5) and `half_cells` the half size in voxels, so the box is symmetric about `center`.
// `faces`: bit 0 = -x, 1 = +x, 2 = -y, 3 = +y, 4 = -z, 5 = +z.
inline PointCloud box(const Vec3& center, int half_cells, int faces = 63,
                      Rgb colour = {200, 100, 50}) {
  PointCloud c;
  const int h = half_cells;
  for (int i = -h; i <= h; ++i)
    for (int j = -h; j <= h; ++j)
      for (int k = -h; k <= h; ++k) {
        const bool on = ((faces & 1) && i == -h) || ((faces & 2) && i == h) ||
                        ((faces & 4) && j == -h) || ((faces & 8) && j == h) ||
                        ((faces & 16) && k == -h) || ((faces & 32) && k == h);
        if (on) c.push_back((center + 0.01 * Vec3(i, j, k)).cast<float>(), colour);
      }
  return c;
}

// An instance of one keyframe (no pose, score 0.8).
inline Observation instance(double t, std::optional<int> track_id, const std::string& cls,
                            PointCloud points, double score = 0.8) {
  Observation o;
  o.timestamp = t;
  o.track_id = track_id;
  o.class_name = cls;
  o.score = score;
  o.points_in_world = std::move(points);
  return o;
}

}  // namespace objmap::fusion::test
