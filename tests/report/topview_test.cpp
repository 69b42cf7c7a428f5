#include "objmap/report/topview.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <opencv2/core.hpp>
#include <vector>

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
  ASSERT_GE(drawn.map_width_px, bare.image.cols);
  EXPECT_GT(cv::norm(drawn.image(cv::Rect(0, 0, bare.image.cols, bare.image.rows)), bare.image,
                     cv::NORM_L1),
            0.0);
}

// `cloud` handed over in blocks of `size` points (the last one shorter), as a file read in
// blocks hands it.
PointBlocks in_blocks(const PointCloud& cloud, std::size_t size) {
  return [&cloud, size](const std::function<void(const PointCloud&)>& take) {
    for (std::size_t first = 0; first < cloud.size(); first += size) {
      PointCloud block;
      for (std::size_t i = first; i < std::min(cloud.size(), first + size); ++i)
        block.push_back(cloud.points[i], cloud.colors[i]);
      take(block);
    }
  };
}

TEST(TopView, AMapReadInBlocksGivesTheViewOfTheWholeMap) {
  // A noisy floor with stray points (the extent clips them) and overlapping heights, 7 blocks.
  PointCloud cloud;
  for (int i = 0; i < 20000; ++i) {
    const float x = 0.0001f * static_cast<float>((i * 7919) % 20000);
    const float y = 0.0001f * static_cast<float>((i * 104729) % 17389);
    cloud.push_back(Vec3f(x, y, 0.001f * static_cast<float>(i % 97)),
                    Rgb{static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(i / 256), 40});
  }
  cloud.push_back(Vec3f(30.0f, -20.0f, 1.0f), Rgb{0, 0, 0});
  TopViewOptions options;
  options.pixel_m = 0.01;
  options.point_size_m = 0.02;
  TopViewObject block;
  block.id = 1;
  block.label = "1 cup";
  block.obb.center = Vec3(1.0, 0.8, 0.1);
  block.obb.half_extent = Vec3(0.05, 0.05, 0.05);
  const TopView whole = render_top_view(cloud, {block}, options);
  const TopView blocks = render_top_view(in_blocks(cloud, 3000), cloud.size(), {block}, options);
  ASSERT_EQ(blocks.image.size(), whole.image.size());
  EXPECT_EQ(cv::norm(blocks.image, whole.image, cv::NORM_L1), 0.0);
  EXPECT_EQ(blocks.origin_a, whole.origin_a);
  EXPECT_EQ(blocks.origin_b, whole.origin_b);
}

// 31 chairs round two tables 1.6 m apart (16 and 15 on circles of 0.7 m), as on a real
// walk-through of a meeting room.
std::vector<TopViewObject> chairs_round_two_tables() {
  std::vector<TopViewObject> chairs;
  for (int i = 0; i < 31; ++i) {
    const int table = i < 16 ? 0 : 1, n = table == 0 ? 16 : 15, k = table == 0 ? i : i - 16;
    const double a = 2 * M_PI * k / n;
    TopViewObject o;
    o.id = 100 + i;
    o.label = std::to_string(o.id) + " chair";
    o.obb.center = Vec3(1.6 * table + 0.7 * std::cos(a), 0.7 * std::sin(a), 0.45);
    o.obb.half_extent = Vec3(0.22, 0.22, 0.45);
    o.color = Rgb{200, 120, 0};
    chairs.push_back(o);
  }
  return chairs;
}

TEST(TopView, CrowdedLabelsNeverOverlapAndTheRestAreListedBeside) {
  PointCloud floor;
  for (int i = 0; i < 60; ++i)
    for (int j = 0; j < 40; ++j) floor.push_back(Vec3f(-1.0f + 0.06f * i, -1.2f + 0.06f * j, 0.0f));
  const std::vector<TopViewObject> chairs = chairs_round_two_tables();
  TopViewOptions options;
  options.pixel_m = 0.01;
  const TopView view = render_top_view(floor, chairs, options);
  ASSERT_EQ(view.labels.size(), chairs.size());
  int whole = 0, listed = 0;
  for (std::size_t i = 0; i < view.labels.size(); ++i) {
    const TopViewLabel& a = view.labels[i];
    EXPECT_EQ(a.id, chairs[i].id);
    a.listed ? ++listed : ++whole;
    if (a.box.area() == 0) {
      EXPECT_TRUE(a.listed) << a.id << ": neither on the map nor listed";
      continue;
    }
    // On the map, inside it, over no other label.
    EXPECT_LE(a.box.x + a.box.width, view.map_width_px) << a.id;
    for (std::size_t j = 0; j < i; ++j)
      EXPECT_EQ((a.box & view.labels[j].box).area(), 0) << a.id << " over " << view.labels[j].id;
  }
  EXPECT_EQ(whole + listed, 31);
  EXPECT_GT(whole, 0);
  // A list beside the map exactly when a label is in it.
  EXPECT_EQ(view.image.cols > view.map_width_px, listed > 0) << listed;

  // The same chairs drawn at a quarter of the size crowd more: more labels go to the list, still
  // none over another.
  options.pixel_m = 0.04;
  const TopView small = render_top_view(floor, chairs, options);
  int small_listed = 0;
  for (std::size_t i = 0; i < small.labels.size(); ++i) {
    small_listed += small.labels[i].listed;
    for (std::size_t j = 0; j < i; ++j)
      EXPECT_EQ((small.labels[i].box & small.labels[j].box).area(), 0);
  }
  EXPECT_GT(small_listed, listed);
  EXPECT_GT(small.image.cols, small.map_width_px);
}

TEST(TopView, BadOptionsAreNamed) {
  TopViewOptions options;
  options.up_axis = 3;
  EXPECT_THROW(render_top_view(PointCloud{}, {}, options), InputError);
}

}  // namespace
}  // namespace objmap::report
