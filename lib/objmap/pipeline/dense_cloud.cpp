#include "objmap/pipeline/dense_cloud.h"

#include <algorithm>

#include "objmap/fusion/voxel_map.h"

namespace objmap::pipeline {

DenseCloud take_dense_cloud(fusion::VoxelMap& dense, const fusion::VoxelMapOptions& options) {
  DenseCloud out;
  fusion::VoxelMap::VoxelPoints voxels = dense.take_sorted_points();  // frees the map
  dense = fusion::VoxelMap(options);
  const std::size_t n = voxels.size();
  out.cloud.points.resize(n);
  out.cloud.colors.resize(n);
  out.keys.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    out.cloud.points[i] = voxels[i].point;
    out.cloud.colors[i] = voxels[i].color();
    out.keys[i] = voxels[i].key;
  }
  return out;
}

std::vector<Rgb> semantic_colors(const DenseCloud& dense, double voxel_m,
                                 const std::vector<fusion::ObjectRecord>& records,
                                 const std::vector<Rgb>& record_color) {
  const geometry::VoxelHashTable<std::uint32_t> owner = fusion::voxel_owners(records, voxel_m);
  // The owned voxels (tens of thousands) are looked up in the dense keys (sorted, unique), rather
  // than each of the millions of dense voxels in `owner`.
  std::vector<Rgb> colors = dense.cloud.colors;
  owner.for_each([&](fusion::VoxelKey key, std::uint32_t slot) {
    const auto it = std::lower_bound(dense.keys.begin(), dense.keys.end(), key);
    if (it != dense.keys.end() && *it == key)
      colors[static_cast<std::size_t>(it - dense.keys.begin())] = record_color[slot - 1];
  });
  return colors;
}

std::size_t drop_sighting_voxels(DenseCloud& dense,
                                 const std::vector<fusion::ObjectRecord>& sightings,
                                 const std::vector<fusion::ObjectRecord>& objects, double voxel_m) {
  if (sightings.empty() || dense.keys.empty()) return 0;
  const geometry::VoxelHashTable<std::uint32_t> moving = fusion::voxel_owners(sightings, voxel_m);
  const geometry::VoxelHashTable<std::uint32_t> staying = fusion::voxel_owners(objects, voxel_m);
  std::vector<char> drop(dense.keys.size(), 0);
  moving.for_each([&](fusion::VoxelKey key, std::uint32_t) {
    if (staying.contains(key)) return;
    const auto it = std::lower_bound(dense.keys.begin(), dense.keys.end(), key);
    if (it != dense.keys.end() && *it == key)
      drop[static_cast<std::size_t>(it - dense.keys.begin())] = 1;
  });
  return drop_points(dense, drop);
}

std::size_t drop_points(DenseCloud& dense, const std::vector<char>& drop) {
  std::size_t kept = 0;
  for (std::size_t i = 0; i < dense.keys.size(); ++i) {
    if (drop[i]) continue;
    dense.cloud.points[kept] = dense.cloud.points[i];
    dense.cloud.colors[kept] = dense.cloud.colors[i];
    dense.keys[kept] = dense.keys[i];
    ++kept;
  }
  const std::size_t dropped = dense.keys.size() - kept;
  dense.cloud.points.resize(kept);
  dense.cloud.colors.resize(kept);
  dense.keys.resize(kept);
  return dropped;
}

}  // namespace objmap::pipeline
