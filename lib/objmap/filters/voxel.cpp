#include "objmap/filters/voxel.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "objmap/core/error.h"
#include "objmap/geometry/voxel_key.h"

namespace objmap::filters {

void VoxelFilterOptions::check() const {
  require(std::isfinite(voxel_m) && voxel_m >= 1e-4 && voxel_m <= 100.0,
          "VoxelFilterOptions.voxel_m",
          "must be in [0.0001, 100] metres, got " + std::to_string(voxel_m));
}

VoxelFilterResult voxel_filter(const PointCloud& cloud, const VoxelFilterOptions& options) {
  using geometry::kNoVoxel;
  using geometry::VoxelKey;
  options.check();
  VoxelFilterResult result;
  const std::size_t n = cloud.size();
  const bool colour = cloud.has_colors();
  const float inv = static_cast<float>(1.0 / options.voxel_m);

  // 1. Each point's voxel; a first-seen index per voxel.
  geometry::VoxelHashTable<std::uint32_t> slot_of;  // stores slot + 1 (0 = new)
  slot_of.reserve(n / 4 + 16);
  std::vector<VoxelKey> keys;
  std::vector<std::uint32_t> slot_of_point(n, VoxelFilterResult::kDropped);
  for (std::size_t i = 0; i < n; ++i) {
    const VoxelKey key = geometry::voxel_key(cloud.points[i], inv);
    if (key == kNoVoxel) {
      ++result.dropped;
      continue;
    }
    std::uint32_t& s = slot_of[key];
    if (s == 0) {
      keys.push_back(key);
      s = static_cast<std::uint32_t>(keys.size());
    }
    slot_of_point[i] = s - 1;
  }

  // 2. Output order: sorted by key, so the result does not depend on the input order of voxels.
  std::vector<std::uint32_t> order(keys.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(),
            [&](std::uint32_t a, std::uint32_t b) { return keys[a] < keys[b]; });
  std::vector<std::uint32_t> rank(keys.size());
  for (std::uint32_t r = 0; r < order.size(); ++r) rank[order[r]] = r;

  // 3. Centroid and mean colour per voxel, in input order (deterministic sums).
  const std::size_t m = keys.size();
  std::vector<Eigen::Vector3d> sum(m, Eigen::Vector3d::Zero());
  std::vector<std::uint32_t> csum(colour ? 3 * m : 0, 0);
  result.counts.assign(m, 0);
  result.voxel_of_point.assign(n, VoxelFilterResult::kDropped);
  for (std::size_t i = 0; i < n; ++i) {
    if (slot_of_point[i] == VoxelFilterResult::kDropped) continue;
    const std::uint32_t r = rank[slot_of_point[i]];
    result.voxel_of_point[i] = r;
    sum[r] += cloud.points[i].cast<double>();
    ++result.counts[r];
    if (colour) {
      csum[3 * r] += cloud.colors[i].r;
      csum[3 * r + 1] += cloud.colors[i].g;
      csum[3 * r + 2] += cloud.colors[i].b;
    }
  }
  result.kept.points.resize(m);
  if (colour) result.kept.colors.resize(m);
  for (std::size_t r = 0; r < m; ++r) {
    const double c = result.counts[r];
    result.kept.points[r] = (sum[r] / c).cast<float>();
    if (colour) {
      auto avg = [&](std::uint32_t s) {
        return static_cast<std::uint8_t>((s + result.counts[r] / 2) / result.counts[r]);
      };
      result.kept.colors[r] = Rgb{avg(csum[3 * r]), avg(csum[3 * r + 1]), avg(csum[3 * r + 2])};
    }
  }
  return result;
}

}  // namespace objmap::filters
