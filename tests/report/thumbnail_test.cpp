#include "objmap/report/thumbnail.h"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "objmap/core/error.h"

namespace objmap::report {
namespace {

// A red square (z = 0.1) floating over a larger blue one (z = 0), 1 cm steps.
PointCloud two_layers() {
  PointCloud cloud;
  for (int i = -10; i <= 10; ++i)
    for (int j = -10; j <= 10; ++j) {
      cloud.push_back(Vec3f(0.01f * i, 0.01f * j, 0.0f), Rgb{0, 0, 255});
      if (std::abs(i) <= 5 && std::abs(j) <= 5)
        cloud.push_back(Vec3f(0.01f * i, 0.01f * j, 0.1f), Rgb{255, 0, 0});
    }
  return cloud;
}

TEST(Thumbnail, NearestPointWinsAndTheObjectFillsTheImage) {
  ThumbnailOptions options;
  options.elevation_deg = 89;  // from straight above: the red layer hides the blue one's middle
  options.clip_percent = 0;
  const cv::Mat image = render_thumbnail(two_layers(), "", options);
  ASSERT_EQ(image.type(), CV_8UC3);
  ASSERT_EQ(image.rows, 160);
  ASSERT_EQ(image.cols, 160);
  const cv::Vec3b middle = image.at<cv::Vec3b>(80, 80);  // BGR
  EXPECT_GT(middle[2], 200);
  EXPECT_LT(middle[0], 30);
  // the blue layer frames it, 20 cm fitted into ~148 px: a pixel 60 px from the centre is blue
  const cv::Vec3b side = image.at<cv::Vec3b>(80, 20);
  EXPECT_GT(side[0], 100);
  EXPECT_LT(side[2], 30);
  // no white hole between 1 cm points (squares of 1 cm): every pixel of the middle row is coloured
  int white = 0;
  for (int u = 14; u < 146; ++u) white += image.at<cv::Vec3b>(80, u) == cv::Vec3b(255, 255, 255);
  EXPECT_EQ(white, 0);
}

TEST(Thumbnail, ObliqueViewShowsBothLayersAndTheLabel) {
  ThumbnailOptions options;
  options.size_px = 120;
  const cv::Mat image = render_thumbnail(two_layers(), "7 cup", options);
  ASSERT_EQ(image.rows, 120);
  int red = 0, blue = 0;
  for (int v = 0; v < image.rows; ++v)
    for (int u = 0; u < image.cols; ++u) {
      const cv::Vec3b p = image.at<cv::Vec3b>(v, u);
      red += p[2] > 120 && p[0] < 60;
      blue += p[0] > 120 && p[2] < 60;
    }
  EXPECT_GT(red, 300);
  EXPECT_GT(blue, 300);
  // the label is dark text in the top-left band
  int dark = 0;
  for (int v = 2; v < 18; ++v)
    for (int u = 2; u < 60; ++u) dark += cv::norm(image.at<cv::Vec3b>(v, u)) < 150;
  EXPECT_GT(dark, 20);
}

TEST(Thumbnail, EmptyCloudIsBlankAndBadOptionsAreNamed) {
  const cv::Mat blank = render_thumbnail(PointCloud{}, "", {});
  EXPECT_EQ(cv::countNonZero(blank.reshape(1) != 255), 0);
  ThumbnailOptions options;
  options.elevation_deg = 90;
  try {
    render_thumbnail(two_layers(), "x", options);
    FAIL() << "no throw";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("ThumbnailOptions.elevation_deg"), std::string::npos);
  }
}

}  // namespace
}  // namespace objmap::report
