#include "objmap/filters/outlier.h"

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <thread>

#include "objmap/core/error.h"

namespace objmap::filters {

void OutlierOptions::check() const {
  require(neighbours >= 1, "OutlierOptions.neighbours",
          "must be >= 1, got " + std::to_string(neighbours));
  require(std::isfinite(std_ratio), "OutlierOptions.std_ratio",
          "must be finite, got " + std::to_string(std_ratio));
  require(threads >= 1, "OutlierOptions.threads", "must be >= 1, got " + std::to_string(threads));
}

OutlierResult remove_outliers(const PointCloud& cloud, const OutlierOptions& options) {
  options.check();
  OutlierResult result;
  const std::size_t n = cloud.size();
  const int k = options.neighbours;
  if (n <= static_cast<std::size_t>(k)) {
    result.kept = cloud;
    result.keep_mask.assign(n, true);
    result.threshold = std::numeric_limits<double>::infinity();
    return result;
  }

  auto pcl_cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  pcl_cloud->resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3f& p = cloud.points[i];
    (*pcl_cloud)[i] = pcl::PointXYZ(p.x(), p.y(), p.z());
  }
  pcl::KdTreeFLANN<pcl::PointXYZ> tree(/*sorted=*/true);
  tree.setInputCloud(pcl_cloud);

  // 1. d_i: mean distance to the K nearest neighbours (the first hit, the point itself, skipped).
  std::vector<double> mean_distance(n);
  auto work = [&](std::size_t begin, std::size_t end) {
    std::vector<int> idx(k + 1);
    std::vector<float> sq(k + 1);
    for (std::size_t i = begin; i < end; ++i) {
      const int found = tree.nearestKSearch((*pcl_cloud)[i], k + 1, idx, sq);
      double sum = 0.0;
      for (int j = 1; j < found; ++j) sum += std::sqrt(static_cast<double>(sq[j]));
      mean_distance[i] = found > 1 ? sum / (found - 1) : 0.0;
    }
  };
  const int threads = std::max(1, std::min<int>(options.threads, static_cast<int>(n / 1024) + 1));
  if (threads == 1) {
    work(0, n);
  } else {
    std::vector<std::thread> pool;
    const std::size_t chunk = (n + threads - 1) / threads;
    for (int t = 1; t < threads; ++t)
      pool.emplace_back(work, std::min(n, t * chunk), std::min(n, (t + 1) * chunk));
    work(0, std::min(n, chunk));
    for (auto& th : pool) th.join();
  }

  // 2. Eq 18: m, s over the cloud (in index order, so the sums do not depend on threads), t = m +
  // k·s.
  double sum = 0.0, sq_sum = 0.0;
  for (double d : mean_distance) {
    sum += d;
    sq_sum += d * d;
  }
  const double m = sum / static_cast<double>(n);
  const double variance =
      (sq_sum - sum * sum / static_cast<double>(n)) / static_cast<double>(n - 1);
  const double s = std::sqrt(std::max(0.0, variance));
  result.mean_distance = m;
  result.std_distance = s;
  result.threshold = m + options.std_ratio * s;

  // 3. Keep d_i <= t.
  result.keep_mask.resize(n);
  const bool colour = cloud.has_colors();
  result.kept.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const bool keep = mean_distance[i] <= result.threshold;
    result.keep_mask[i] = keep;
    if (!keep) continue;
    if (colour)
      result.kept.push_back(cloud.points[i], cloud.colors[i]);
    else
      result.kept.push_back(cloud.points[i]);
  }
  return result;
}

}  // namespace objmap::filters
