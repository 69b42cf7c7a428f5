#pragma once
#include <cstddef>
#include <vector>

#include "objmap/core/types.h"

namespace objmap::filters {

// Keeps an object's main body: Euclidean clustering (PCL's EuclideanClusterExtraction, points
// closer than `tolerance_m` are connected) and only the largest cluster plus the clusters at least
// `keep_ratio` of its size. Removes what eq 18 cannot: a whole patch of background or table that a
// loose mask carried into the object (mask borders on depth edges), which is dense and so not an
// outlier by the mean k-NN distance.
struct ClusterOptions {
  double tolerance_m =
      0.03;  // 3 cm: bridges Kinect holes on one surface at 2-3 m, not a gap to a wall
  double keep_ratio =
      0.3;             // other clusters kept when at least 30% of the largest (a chair's parts)
  int min_points = 3;  // clusters smaller than this are always dropped
  void check() const;  // throws InputError naming the bad field
};

struct ClusterResult {
  PointCloud kept;              // the kept points, in input order
  std::vector<bool> keep_mask;  // one flag per input point
  std::size_t clusters = 0;     // clusters found
  std::size_t clusters_kept = 0;
};

ClusterResult keep_main_clusters(const PointCloud& cloud, const ClusterOptions& options = {});

}  // namespace objmap::filters
