#pragma once
#include <cstddef>
#include <vector>

// Summary statistics of a list of errors, computed as the TUM RGB-D benchmark tools print them
// (evaluate_ate.py / evaluate_rpe.py with numpy): rmse = sqrt(Σe²/n), the median of an even count
// is the mean of the two middle values, the standard deviation is the population one (ddof = 0).
namespace objmap::eval {

struct ErrorStats {
  std::size_t count = 0;  // n; all other fields are 0 when n = 0
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;
  double stddev = 0.0;  // population standard deviation (numpy.std)
  double min = 0.0;
  double max = 0.0;
};

ErrorStats compute_stats(const std::vector<double>& errors);

}  // namespace objmap::eval
