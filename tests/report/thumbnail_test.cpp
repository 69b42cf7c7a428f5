#include "objmap/report/thumbnail.h"

#include <gtest/gtest.h>

#include <set>

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

// A closed axis-aligned box of 12 triangles, 20 x 20 x 10 cm, its base on z = 0.
TriangleMesh box_mesh() {
  TriangleMesh m;
  for (int k = 0; k < 8; ++k)
    m.vertices.push_back(Vec3f(k & 1 ? 0.1f : -0.1f, k & 2 ? 0.1f : -0.1f, k & 4 ? 0.1f : 0.0f));
  const int faces[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1},
                           {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
  for (const auto& f : faces) {
    m.triangles.push_back({static_cast<std::uint32_t>(f[0]), static_cast<std::uint32_t>(f[1]),
                           static_cast<std::uint32_t>(f[2])});
    m.triangles.push_back({static_cast<std::uint32_t>(f[0]), static_cast<std::uint32_t>(f[2]),
                           static_cast<std::uint32_t>(f[3])});
  }
  return m;
}

TEST(Thumbnail, MeshIsFilledAndItsFacesShadedApart) {
  ThumbnailOptions options;
  options.clip_percent = 0;
  const cv::Mat image = render_mesh_thumbnail(box_mesh(), Rgb{40, 200, 60}, "1 box", options);
  // Filled: no white pixel on the row through the box's middle between its outline.
  int coloured = 0, white = 0;
  for (int u = 20; u < 140; ++u) {
    const cv::Vec3b p = image.at<cv::Vec3b>(95, u);
    (p == cv::Vec3b(255, 255, 255) ? white : coloured)++;
  }
  EXPECT_GT(coloured, 90);
  // Every coloured pixel is the class colour shaded (green dominant); the top and a side face
  // differ in brightness.
  std::set<int> greens;
  for (int v = 20; v < 150; ++v)
    for (int u = 6; u < 154; ++u) {
      const cv::Vec3b p = image.at<cv::Vec3b>(v, u);
      if (p == cv::Vec3b(255, 255, 255) || p == cv::Vec3b(210, 210, 210)) continue;
      if (p[1] > p[0] && p[1] > p[2]) greens.insert(p[1] / 8);
    }
  EXPECT_GE(greens.size(), 2u) << "at least two shades: the faces are told apart";
  // An empty mesh: a blank labelled image.
  const cv::Mat blank = render_mesh_thumbnail(TriangleMesh{}, Rgb{1, 2, 3}, "", options);
  EXPECT_EQ(cv::countNonZero(blank.reshape(1) != 255), 0);
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
