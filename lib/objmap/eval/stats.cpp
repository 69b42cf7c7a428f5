#include "objmap/eval/stats.h"

#include <algorithm>
#include <cmath>

namespace objmap::eval {

ErrorStats compute_stats(const std::vector<double>& errors) {
  ErrorStats s;
  s.count = errors.size();
  if (errors.empty()) return s;
  const double n = static_cast<double>(errors.size());
  double sum = 0.0, sum_sq = 0.0;
  for (double e : errors) {
    sum += e;
    sum_sq += e * e;
  }
  s.rmse = std::sqrt(sum_sq / n);
  s.mean = sum / n;
  double var = 0.0;  // two-pass, as numpy.std
  for (double e : errors) var += (e - s.mean) * (e - s.mean);
  s.stddev = std::sqrt(var / n);
  std::vector<double> sorted = errors;
  std::sort(sorted.begin(), sorted.end());
  const std::size_t mid = sorted.size() / 2;
  s.median = sorted.size() % 2 == 1 ? sorted[mid] : 0.5 * (sorted[mid - 1] + sorted[mid]);
  s.min = sorted.front();
  s.max = sorted.back();
  return s;
}

}  // namespace objmap::eval
