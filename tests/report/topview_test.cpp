#include "objmap/report/topview.h"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "objmap/core/error.h"

namespace objmap::report {
namespace {

TEST(TopView, HighestPointWinsAndObjectsAreDrawn) {
  PointCloud cloud;
  // A red floor at z = 0 and a blue 10 cm block at z = 0.5 above its middle, 1 x 1 m, 1 cm steps.
  for (int i = 0; i < 100; ++i)
    for (int j = 0; j < 100; ++j) {
      cloud.push_back(Vec3f(0.01f * i, 0.01f * j, 0.0f), Rgb{255, 0, 0});
      if (i >= 45 && i < 55 && j >= 45 && j < 55)
        cloud.push_back(Vec3f(0.01f * i, 0.01f * j, 0.5f), Rgb{0, 0, 255});
    }
  TopViewOptions options;
  options.pixel_m = 0.02;  // 2 points per pixel side: no pixel left empty
  options.margin_px = 10;
  options.clip_percent = 0;
  const TopView bare = render_top_view(cloud, {}, options);
  ASSERT_EQ(bare.image.type(), CV_8UC3);
  EXPECT_NEAR(bare.image.cols, 70, 2);
  // The middle pixel shows the block (blue in BGR), a corner of the floor shows red.
  const auto middle = bare.image.at<cv::Vec3b>(bare.image.rows / 2, bare.image.cols / 2);
  EXPECT_EQ(middle, cv::Vec3b(255, 0, 0));
  const auto floor = bare.image.at<cv::Vec3b>(15, 15);
  EXPECT_EQ(floor, cv::Vec3b(0, 0, 255));

  TopViewObject block;
  block.id = 1;
  block.label = "1 cup";
  block.obb.center = Vec3(0.5, 0.5, 0.5);
  block.obb.half_extent = Vec3(0.05, 0.05, 0.05);
  block.color = Rgb{0, 255, 0};
  const TopView drawn = render_top_view(cloud, {block}, options);
  EXPECT_GT(cv::norm(drawn.image, bare.image, cv::NORM_L1), 0.0);
}

TEST(TopView, BadOptionsAreNamed) {
  TopViewOptions options;
  options.up_axis = 3;
  EXPECT_THROW(render_top_view(PointCloud{}, {}, options), InputError);
}

}  // namespace
}  // namespace objmap::report
