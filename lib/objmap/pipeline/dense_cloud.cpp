#include "objmap/pipeline/dense_cloud.h"

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

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

namespace {

// f(index in dense.keys, slot) for each voxel of `owner` that the dense cloud holds. The owned
// voxels (tens to hundreds of thousands) are sorted and walked along the dense keys (sorted,
// unique: millions), each found by a galloping search from the one before: the search stays near
// where it was, rather than starting each of them at the middle of the whole array.
template <typename F>
void for_each_dense_voxel_of(const DenseCloud& dense,
                             const geometry::VoxelHashTable<std::uint32_t>& owner, F&& f) {
  std::vector<std::pair<fusion::VoxelKey, std::uint32_t>> owned;
  owned.reserve(owner.size());
  owner.for_each([&](fusion::VoxelKey key, std::uint32_t slot) { owned.emplace_back(key, slot); });
  std::sort(owned.begin(), owned.end());
  const auto end = dense.keys.end();
  auto at = dense.keys.begin();  // every key before it is below the next owned key
  for (const auto& [key, slot] : owned) {
    std::size_t step = 1;
    auto bound = at;  // end, or a key not below `key`
    while (bound != end && *bound < key) {
      at = bound + 1;
      bound =
          static_cast<std::size_t>(end - at) > step ? at + static_cast<std::ptrdiff_t>(step) : end;
      step *= 2;
    }
    at = std::lower_bound(at, bound, key);
    if (at != end && *at == key) f(static_cast<std::size_t>(at - dense.keys.begin()), slot);
  }
}

}  // namespace

std::vector<Rgb> semantic_colors(const DenseCloud& dense, double voxel_m,
                                 const std::vector<fusion::ObjectRecord>& records,
                                 const std::vector<Rgb>& record_color) {
  const geometry::VoxelHashTable<std::uint32_t> owner = fusion::voxel_owners(records, voxel_m);
  std::vector<Rgb> colors = dense.cloud.colors;
  for_each_dense_voxel_of(
      dense, owner, [&](std::size_t i, std::uint32_t slot) { colors[i] = record_color[slot - 1]; });
  return colors;
}

std::size_t drop_sighting_voxels(DenseCloud& dense,
                                 const std::vector<fusion::ObjectRecord>& sightings,
                                 const std::vector<fusion::ObjectRecord>& objects, double voxel_m) {
  if (sightings.empty() || dense.keys.empty()) return 0;
  const geometry::VoxelHashTable<std::uint32_t> moving = fusion::voxel_owners(sightings, voxel_m);
  const geometry::VoxelHashTable<std::uint32_t> staying = fusion::voxel_owners(objects, voxel_m);
  std::vector<char> drop(dense.keys.size(), 0);
  for_each_dense_voxel_of(dense, moving, [&](std::size_t i, std::uint32_t) {
    if (!staying.contains(dense.keys[i])) drop[i] = 1;
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
