#pragma once
#include <cstdint>
#include <limits>
#include <vector>

#include "objmap/core/types.h"

namespace objmap::filters {

// Voxel-grid filter (paper §3.3, the last step of an object's cloud): one point per occupied voxel,
// at the centroid of the voxel's points, with their mean colour (like PCL's VoxelGrid). Voxels are
// floor(point / voxel_m) on the world grid, the same grid as the fusion maps
// (geometry/voxel_key.h).
struct VoxelFilterOptions {
  double voxel_m = 0.01;  // leaf size; 1 cm as the dense map
  void check() const;     // throws InputError naming the bad field
};

struct VoxelFilterResult {
  PointCloud kept;  // one point per voxel, sorted by voxel (x, then y, then z)
  std::vector<std::uint32_t> voxel_of_point;  // per input point: index into `kept`, or kDropped
  std::vector<std::uint32_t> counts;          // per kept point: how many input points it stands for
  std::size_t dropped = 0;  // input points that were not finite or out of key range
  static constexpr std::uint32_t kDropped = std::numeric_limits<std::uint32_t>::max();
};

VoxelFilterResult voxel_filter(const PointCloud& cloud, const VoxelFilterOptions& options = {});

}  // namespace objmap::filters
