#include "objmap/filters/outlier.h"

#include <gtest/gtest.h>

#include "objmap/core/error.h"

namespace objmap::filters {
namespace {

PointCloud sample_plane(double side, double step) {
  PointCloud cloud;
  const int n = static_cast<int>(side / step + 0.5);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      cloud.push_back(Vec3f(static_cast<float>(i * step), static_cast<float>(j * step), 1.0f),
                      Rgb{static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(j), 7});
  return cloud;
}

TEST(Outlier, RemovesIsolatedPointsKeepsTheSurface) {
  PointCloud plane = sample_plane(/*side=*/1.0, /*step=*/0.01);  // 10k points
  plane.push_back({5.0f, 5.0f, 5.0f}, Rgb{1, 2, 3});             // one far outlier
  const auto result = remove_outliers(plane, {});
  ASSERT_EQ(result.keep_mask.size(), plane.size());
  EXPECT_FALSE(result.keep_mask.back());
  EXPECT_GE(result.kept.size(), plane.size() - 1 - plane.size() / 100);  // borders may go, not more
  EXPECT_TRUE(result.kept.has_colors());
  EXPECT_GT(result.threshold, result.mean_distance);
  // The kept cloud is the masked input, in order.
  std::size_t j = 0;
  for (std::size_t i = 0; i < plane.size(); ++i)
    if (result.keep_mask[i]) {
      EXPECT_EQ(result.kept.points[j++], plane.points[i]);
    }
  EXPECT_EQ(j, result.kept.size());
}

TEST(Outlier, SameResultForAnyThreadCount) {
  PointCloud plane = sample_plane(0.6, 0.01);
  for (int i = 0; i < 50; ++i) plane.push_back(Vec3f(0.1f * i, 3.0f, 0.02f * i));
  OutlierOptions one, two;
  two.threads = 2;
  const auto a = remove_outliers(plane, one);
  const auto b = remove_outliers(plane, two);
  EXPECT_EQ(a.keep_mask, b.keep_mask);
  EXPECT_EQ(a.threshold, b.threshold);
}

TEST(Outlier, SmallCloudIsKeptWholeAndBadOptionsAreNamed) {
  PointCloud few;
  for (int i = 0; i < 5; ++i) few.push_back(Vec3f(static_cast<float>(i), 0, 0));
  const auto r = remove_outliers(few, {});
  EXPECT_EQ(r.kept.size(), 5u);
  OutlierOptions bad;
  bad.neighbours = 0;
  try {
    remove_outliers(few, bad);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "OutlierOptions.neighbours: must be >= 1, got 0");
  }
}

}  // namespace
}  // namespace objmap::filters
