// Euclidean clustering on a grid of hashed cells (detail::euclidean_clusters): the clusters of
// PCL's EuclideanClusterExtraction without its kd-tree (docs/benchmarks.md, "The scene step").
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>
// The template's code, instantiated here: objmap links no libpcl_segmentation, whose load (with
// libpcl_features) cost ~75 ms at the start of every command (docs/architecture.md, "Start-up").
#include <pcl/segmentation/impl/extract_clusters.hpp>

#include <algorithm>

#include "objmap/geometry/voxel_key.h"
#include "objmap/scene/sampled.h"

namespace objmap::scene::detail {

std::vector<std::vector<int>> pcl_euclidean_clusters(const std::vector<Vec3f>& points, double gap_m,
                                                     std::size_t min_points) {
  Cloud::Ptr cloud(new Cloud);
  cloud->reserve(points.size());
  for (const Vec3f& p : points) cloud->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
  tree->setInputCloud(cloud);
  pcl::EuclideanClusterExtraction<pcl::PointXYZ> extract;
  extract.setClusterTolerance(gap_m);
  extract.setMinClusterSize(static_cast<int>(min_points));
  extract.setMaxClusterSize(std::numeric_limits<int>::max());
  extract.setSearchMethod(tree);
  extract.setInputCloud(cloud);
  std::vector<pcl::PointIndices> found;
  extract.extract(found);
  std::vector<std::vector<int>> out;
  for (auto& c : found) out.push_back(std::move(c.indices));
  return out;
}

std::vector<std::vector<int>> euclidean_clusters(const std::vector<Vec3f>& points, double gap_m,
                                                 std::size_t min_points) {
  const std::size_t n = points.size();
  // 1. Each point's cell, a little wider than the gap: a point's neighbours within the gap lie in
  //    its cell and the 26 around it.
  const float inv_cell = static_cast<float>(1.0 / (gap_m * 1.001));
  std::vector<geometry::VoxelKey> keys(n);
  for (std::size_t i = 0; i < n; ++i) {
    keys[i] = geometry::voxel_key(points[i], inv_cell);
    if (keys[i] == geometry::kNoVoxel) return pcl_euclidean_clusters(points, gap_m, min_points);
  }
  // 2. The points by cell (then index), and where each cell's run starts.
  std::vector<std::uint32_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = static_cast<std::uint32_t>(i);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return keys[a] != keys[b] ? keys[a] < keys[b] : a < b;
  });
  std::vector<std::uint32_t> run_start;  // per cell, its first place in `order`; then n
  geometry::VoxelHashTable<std::uint32_t> cell_of(n / 4 + 16);  // cell index + 1
  for (std::size_t r = 0; r < n; ++r)
    if (r == 0 || keys[order[r]] != keys[order[r - 1]]) {
      run_start.push_back(static_cast<std::uint32_t>(r));
      cell_of[keys[order[r]]] = static_cast<std::uint32_t>(run_start.size());
    }
  run_start.push_back(static_cast<std::uint32_t>(n));
  // 3. As PCL grows a cluster from each point not yet taken (in index order): every point closer
  //    than the gap to one of the cluster's (squared distances in float, compared as PCL's
  //    kd-tree compares them) joins it.
  const float gap = static_cast<float>(gap_m);
  const float gap_sq = static_cast<float>(static_cast<double>(gap) * static_cast<double>(gap));
  const auto& offsets = geometry::neighbourhood_offsets();
  std::vector<char> taken(n, 0);
  std::vector<std::vector<int>> clusters;
  std::vector<int> queue;
  for (std::size_t seed = 0; seed < n; ++seed) {
    if (taken[seed]) continue;
    queue.assign(1, static_cast<int>(seed));
    taken[seed] = 1;
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const Vec3f& p = points[static_cast<std::size_t>(queue[q])];
      const geometry::VoxelKey key = keys[static_cast<std::size_t>(queue[q])];
      for (const geometry::VoxelKey off : offsets) {
        const std::uint32_t* cell = cell_of.find(key + off);
        if (!cell) continue;
        for (std::uint32_t r = run_start[*cell - 1]; r < run_start[*cell]; ++r) {
          const std::uint32_t j = order[r];
          if (taken[j]) continue;
          float d = 0.f;
          for (int a = 0; a < 3; ++a) {
            const float diff = p[a] - points[j][a];
            d += diff * diff;
          }
          if (!(d < gap_sq)) continue;
          taken[j] = 1;
          queue.push_back(static_cast<int>(j));
        }
      }
    }
    if (queue.size() < min_points) continue;
    std::sort(queue.begin(), queue.end());
    clusters.push_back(queue);
  }
  // 4. Largest first, sorted as EuclideanClusterExtraction sorts them.
  std::sort(
      clusters.rbegin(), clusters.rend(),
      [](const std::vector<int>& a, const std::vector<int>& b) { return a.size() < b.size(); });
  return clusters;
}

}  // namespace objmap::scene::detail
