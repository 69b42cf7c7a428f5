#include "objmap/eval/stats.h"

#include <gtest/gtest.h>

#include <cmath>

namespace objmap::eval {
namespace {

TEST(Stats, EvenCountAsNumpy) {
  const ErrorStats s = compute_stats({4.0, 1.0, 3.0, 2.0});
  EXPECT_EQ(s.count, 4u);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(30.0 / 4.0));
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.median, 2.5);              // mean of the two middle values
  EXPECT_DOUBLE_EQ(s.stddev, std::sqrt(1.25));  // population (ddof 0), as numpy.std
  EXPECT_DOUBLE_EQ(s.min, 1.0);
  EXPECT_DOUBLE_EQ(s.max, 4.0);
}

TEST(Stats, OddCountMedianIsTheMiddleValue) {
  const ErrorStats s = compute_stats({5.0, 0.0, 1.0});
  EXPECT_DOUBLE_EQ(s.median, 1.0);
  EXPECT_DOUBLE_EQ(s.mean, 2.0);
}

TEST(Stats, EmptyIsAllZero) {
  const ErrorStats s = compute_stats({});
  EXPECT_EQ(s.count, 0u);
  EXPECT_EQ(s.rmse, 0.0);
  EXPECT_EQ(s.max, 0.0);
}

}  // namespace
}  // namespace objmap::eval
