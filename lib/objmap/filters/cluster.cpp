#include "objmap/filters/cluster.h"

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include <algorithm>
#include <cmath>

#include "objmap/core/error.h"

namespace objmap::filters {

void ClusterOptions::check() const {
  require(std::isfinite(tolerance_m) && tolerance_m > 0 && tolerance_m < 1,
          "ClusterOptions.tolerance_m", "must be in (0, 1) m");
  require(std::isfinite(keep_ratio) && keep_ratio >= 0 && keep_ratio <= 1,
          "ClusterOptions.keep_ratio", "must be in [0, 1]");
  require(min_points >= 1, "ClusterOptions.min_points", "must be >= 1");
}

ClusterResult keep_main_clusters(const PointCloud& cloud, const ClusterOptions& options) {
  options.check();
  ClusterResult result;
  result.keep_mask.assign(cloud.size(), false);
  if (cloud.empty()) return result;

  // 1. Euclidean clusters: region growing over PCL's kd-tree radius search, the algorithm of PCL's
  //    EuclideanClusterExtraction (pcl_segmentation itself is not used: its CMake pulls VTK).
  auto pcl_cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  pcl_cloud->reserve(cloud.size());
  for (const auto& p : cloud.points) pcl_cloud->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  pcl::search::KdTree<pcl::PointXYZ> tree;
  tree.setInputCloud(pcl_cloud);
  std::vector<std::vector<int>> clusters;
  std::vector<bool> seen(cloud.size(), false);
  std::vector<int> neighbours;
  std::vector<float> distances;
  for (std::size_t seed = 0; seed < cloud.size(); ++seed) {
    if (seen[seed]) continue;
    std::vector<int> cluster{static_cast<int>(seed)};
    seen[seed] = true;
    for (std::size_t k = 0; k < cluster.size(); ++k) {
      tree.radiusSearch((*pcl_cloud)[cluster[k]], options.tolerance_m, neighbours, distances);
      for (int n : neighbours) {
        if (seen[n]) continue;
        seen[n] = true;
        cluster.push_back(n);
      }
    }
    if (static_cast<int>(cluster.size()) >= options.min_points)
      clusters.push_back(std::move(cluster));
  }
  result.clusters = clusters.size();
  if (clusters.empty()) return result;

  // 2. The largest cluster and those at least keep_ratio of its size.
  std::size_t largest = 0;
  for (const auto& c : clusters) largest = std::max(largest, c.size());
  for (const auto& c : clusters) {
    if (static_cast<double>(c.size()) < options.keep_ratio * largest) continue;
    ++result.clusters_kept;
    for (int i : c) result.keep_mask[i] = true;
  }
  const bool colors = cloud.has_colors();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!result.keep_mask[i]) continue;
    if (colors)
      result.kept.push_back(cloud.points[i], cloud.colors[i]);
    else
      result.kept.push_back(cloud.points[i]);
  }
  return result;
}

}  // namespace objmap::filters
