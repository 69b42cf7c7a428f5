#include "objmap/filters/cluster.h"

#include <gtest/gtest.h>

#include "objmap/core/error.h"

namespace objmap::filters {
namespace {

// A 20 x 20 cm square of points every 1 cm at height z, shifted by (x0, y0).
void add_square(PointCloud& cloud, float x0, float y0, float z, int n = 20) {
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) cloud.push_back(Vec3f(x0 + 0.01f * i, y0 + 0.01f * j, z));
}

TEST(Cluster, DropsADensePatchOfBackgroundThatOutlierRemovalKeeps) {
  PointCloud cloud;
  add_square(cloud, 0, 0, 1.0f);        // the object: 400 points
  add_square(cloud, 1.0f, 0, 3.0f, 8);  // a patch of wall 2 m behind: 64 points, dense
  const auto result = keep_main_clusters(cloud);
  EXPECT_EQ(result.clusters, 2u);
  EXPECT_EQ(result.clusters_kept, 1u);
  EXPECT_EQ(result.kept.size(), 400u);
  for (std::size_t i = 0; i < cloud.size(); ++i) EXPECT_EQ(result.keep_mask[i], i < 400);
}

TEST(Cluster, KeepsPartsOfComparableSize) {
  PointCloud cloud;
  add_square(cloud, 0, 0, 1.0f);
  add_square(cloud, 0.5f, 0, 1.0f, 15);  // 225 points, 56% of the largest, 30 cm away
  const auto result = keep_main_clusters(cloud);
  EXPECT_EQ(result.clusters_kept, 2u);
  EXPECT_EQ(result.kept.size(), cloud.size());
}

TEST(Cluster, GapsBelowTheToleranceJoin) {
  PointCloud cloud;
  add_square(cloud, 0, 0, 1.0f);
  add_square(cloud, 0.215f, 0, 1.0f, 5);  // 2.5 cm from the square's edge: joined at 3 cm
  EXPECT_EQ(keep_main_clusters(cloud).clusters, 1u);
  ClusterOptions tight;
  tight.tolerance_m = 0.02;
  EXPECT_EQ(keep_main_clusters(cloud, tight).clusters, 2u);
}

TEST(Cluster, EmptyCloudAndBadOptions) {
  EXPECT_TRUE(keep_main_clusters(PointCloud{}).kept.empty());
  ClusterOptions bad;
  bad.keep_ratio = 2;
  EXPECT_THROW(keep_main_clusters(PointCloud{}, bad), InputError);
}

}  // namespace
}  // namespace objmap::filters
