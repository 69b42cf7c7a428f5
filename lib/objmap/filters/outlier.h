#pragma once
#include <vector>

#include "objmap/core/types.h"

namespace objmap::filters {

// Statistical outlier removal, eq 18 of the paper: for each point the mean distance d_i to its K
// nearest neighbours; over the cloud their mean m and standard deviation s; a point is kept when
// d_i <= t = m + k·s. Same rule as PCL's StatisticalOutlierRemoval (sample standard deviation).
struct OutlierOptions {
  int neighbours = 20;     // K; the paper's value is not given, 20 is PCL's common choice
  double std_ratio = 1.0;  // k; smaller removes more, and eats object borders (paper §3.3)
  int threads = 1;         // k-NN queries in parallel; the result is identical for any count
  void check() const;      // throws InputError naming the bad field
};

struct OutlierResult {
  PointCloud kept;              // the kept points in input order (colours kept)
  std::vector<bool> keep_mask;  // one flag per input point, so provenance survives
  double threshold = 0.0;       // t, for run.json (infinity when the cloud has <= K points)
  double mean_distance = 0.0;   // m
  double std_distance = 0.0;    // s
};

// A cloud with at most K points is returned whole (too few points for the statistic).
OutlierResult remove_outliers(const PointCloud& cloud, const OutlierOptions& options = {});

}  // namespace objmap::filters
