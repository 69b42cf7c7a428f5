// scene::detail::euclidean_clusters (private to lib/objmap/scene): PCL's Euclidean clusters on a
// grid, compared with PCL's EuclideanClusterExtraction itself (pcl_euclidean_clusters).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "objmap/scene/sampled.h"

namespace objmap::scene::detail {
namespace {

// Patches of a table-top sample: points on a jittered 4 cm grid in a few rectangles (some closer
// than the gap, some not), with stray points between them, shuffled.
std::vector<Vec3f> patches(std::mt19937& rng) {
  std::uniform_real_distribution<float> jitter(-0.012f, 0.012f), stray(-2.f, 2.f);
  std::vector<Vec3f> points;
  const float x0s[] = {-1.5f, -0.3f, 0.f, 0.9f};
  const float z0s[] = {0.f, 0.72f, 0.75f, 0.45f};
  for (int r = 0; r < 4; ++r)
    for (int i = 0; i < 14 + 3 * r; ++i)
      for (int j = 0; j < 10; ++j)
        points.emplace_back(x0s[r] + 0.04f * i + jitter(rng), -0.5f + 0.04f * j + jitter(rng),
                            z0s[r] + 0.3f * jitter(rng));
  for (int k = 0; k < 300; ++k) points.emplace_back(stray(rng), stray(rng), 0.5f * stray(rng));
  std::shuffle(points.begin(), points.end(), rng);
  return points;
}

TEST(EuclideanClusters, AreThoseOfPclsEuclideanClusterExtraction) {
  for (unsigned seed = 1; seed <= 6; ++seed) {
    std::mt19937 rng(seed);
    const std::vector<Vec3f> points = patches(rng);
    for (const double gap : {0.03, 0.06, 0.1})
      for (const std::size_t min_points : {std::size_t{1}, std::size_t{10}, std::size_t{25}}) {
        const auto ours = euclidean_clusters(points, gap, min_points);
        EXPECT_EQ(ours, pcl_euclidean_clusters(points, gap, min_points))
            << "seed " << seed << ", gap " << gap << ", min " << min_points;
        if (gap > 0.05) {  // below the grid's 4 cm every point is alone
          EXPECT_GE(ours.size(), 2u);
        }
      }
  }
}

TEST(EuclideanClusters, PointsExactlyTheGapApartAreApartAsInPcl) {
  // A 1-D chain at 5 cm steps (float) with a gap of 5 cm: PCL's search keeps distances below the
  // radius only, so each point is its own cluster; at 5.01 cm the chain is one.
  std::vector<Vec3f> chain;
  for (int i = 0; i < 20; ++i) chain.emplace_back(0.05f * static_cast<float>(i), 0.f, 0.f);
  EXPECT_EQ(euclidean_clusters(chain, 0.05, 1), pcl_euclidean_clusters(chain, 0.05, 1));
  EXPECT_EQ(euclidean_clusters(chain, 0.0501, 1).size(), 1u);
  EXPECT_EQ(euclidean_clusters(chain, 0.0501, 1), pcl_euclidean_clusters(chain, 0.0501, 1));
}

TEST(EuclideanClusters, PointsBeyondTheGridAreClusteredAsPclDoes) {
  std::mt19937 rng(7);
  std::vector<Vec3f> points = patches(rng);
  points.emplace_back(1e9f, 0.f, 0.f);  // outside the grid's key range
  EXPECT_EQ(euclidean_clusters(points, 0.06, 5), pcl_euclidean_clusters(points, 0.06, 5));
  EXPECT_TRUE(euclidean_clusters({}, 0.06, 1).empty());
}

}  // namespace
}  // namespace objmap::scene::detail
