#include "objmap/filters/outlier.h"

#include <flann/flann.hpp>

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

  // FLANN's single kd-tree (the one PCL's KdTreeFLANN builds: leaves of 15 points, exact search,
  // neighbours sorted by distance), queried a block of points at a time: PCL's one-point
  // nearestKSearch costs an OpenMP region and allocations per query (docs/fusion.md, "Filters").
  static_assert(sizeof(Vec3f) == 3 * sizeof(float), "points must be packed xyz floats");
  flann::Matrix<float> data(const_cast<float*>(cloud.points.front().data()), n, 3);
  flann::Index<flann::L2_Simple<float>> tree(data, flann::KDTreeSingleIndexParams(15));
  tree.buildIndex();

  // 1. d_i: mean distance to the K nearest neighbours (the first hit, the point itself, skipped).
  std::vector<double> mean_distance(n);
  auto work = [&](std::size_t begin, std::size_t end) {
    constexpr std::size_t kBlock = 4096;
    const std::size_t kk = static_cast<std::size_t>(k) + 1;
    std::vector<int> idx(kBlock * kk);
    std::vector<float> sq(kBlock * kk);
    const flann::SearchParams params(-1, 0.0f, /*sorted=*/true);
    for (std::size_t b = begin; b < end; b += kBlock) {
      const std::size_t rows = std::min(kBlock, end - b);
      flann::Matrix<float> queries(data[b], rows, 3);
      flann::Matrix<int> idx_m(idx.data(), rows, kk);
      flann::Matrix<float> sq_m(sq.data(), rows, kk);
      tree.knnSearch(queries, idx_m, sq_m, kk, params);
      for (std::size_t r = 0; r < rows; ++r) {
        const float* d = sq.data() + r * kk;
        double sum = 0.0;
        for (std::size_t j = 1; j < kk; ++j) sum += std::sqrt(static_cast<double>(d[j]));
        mean_distance[b + r] = sum / static_cast<double>(kk - 1);
      }
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
