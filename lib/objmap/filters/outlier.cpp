#include "objmap/filters/outlier.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "objmap/core/error.h"
#include "objmap/filters/neighbour_distances.h"

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

  // 1. d_i: mean distance to the K nearest neighbours, the point itself excluded (the grid search
  // of neighbour_distances.h, bit for bit FLANN's exact kd-tree's).
  const std::vector<double> mean_distance = mean_neighbour_distances(cloud, k, options.threads);

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
