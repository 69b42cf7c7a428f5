// The Hungarian method against brute force, square and rectangular.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <numeric>
#include <random>

#include "objmap/track/assignment.h"
#include "support/test_support.h"

namespace objmap::track {
namespace {

using objmap::test::assignment_cost;

// Smallest total cost over all assignments of min(rows, cols) pairs, by enumeration.
double brute_force(const Eigen::MatrixXd& cost) {
  const bool transposed = cost.rows() > cost.cols();
  const Eigen::MatrixXd c = transposed ? Eigen::MatrixXd(cost.transpose()) : cost;
  std::vector<int> cols(c.cols());
  std::iota(cols.begin(), cols.end(), 0);
  double best = std::numeric_limits<double>::infinity();
  do {
    double total = 0;
    for (int r = 0; r < c.rows(); ++r) total += c(r, cols[r]);
    best = std::min(best, total);
  } while (std::next_permutation(cols.begin(), cols.end()));
  return best;
}

TEST(Assignment, KnownThreeByThree) {
  Eigen::MatrixXd cost(3, 3);
  cost << 4, 1, 3,  //
      2, 0, 5,      //
      3, 2, 2;
  // Optimum 5: row 0 -> col 1 (1), row 1 -> col 0 (2), row 2 -> col 2 (2).
  const std::vector<int> a = solve_assignment(cost);
  EXPECT_EQ(a, (std::vector<int>{1, 0, 2}));
  EXPECT_DOUBLE_EQ(assignment_cost(cost, a), 5.0);
}

TEST(Assignment, MatchesBruteForceOnRandomMatrices) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uniform(-5.0, 10.0);
  for (int trial = 0; trial < 300; ++trial) {
    const int rows = 1 + trial % 6, cols = 1 + (trial / 6) % 6;
    Eigen::MatrixXd cost(rows, cols);
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) cost(r, c) = uniform(rng);
    const std::vector<int> a = solve_assignment(cost);
    ASSERT_EQ(static_cast<int>(a.size()), rows);
    // One-to-one, min(rows, cols) pairs.
    std::vector<int> used;
    for (int c : a)
      if (c >= 0) used.push_back(c);
    std::sort(used.begin(), used.end());
    EXPECT_EQ(std::unique(used.begin(), used.end()), used.end());
    EXPECT_EQ(static_cast<int>(used.size()), std::min(rows, cols));
    EXPECT_NEAR(assignment_cost(cost, a), brute_force(cost), 1e-9) << rows << "x" << cols;
  }
}

TEST(Assignment, EmptyMatrix) {
  EXPECT_TRUE(solve_assignment(Eigen::MatrixXd(0, 3)).empty());
  EXPECT_EQ(solve_assignment(Eigen::MatrixXd(2, 0)), (std::vector<int>{-1, -1}));
}

}  // namespace
}  // namespace objmap::track
