#include "objmap/pipeline/mask_check.h"

#include <gtest/gtest.h>

#include <string>

#include "objmap/core/error.h"
#include "support/test_support.h"

namespace objmap::pipeline {
namespace {

Camera camera() { return test::small_test_camera(); }

// The point that pixel (u, v)'s centre sees at depth z (camera at the origin).
Vec3f point_at(int u, int v, double z) {
  const Camera c = camera();
  return Vec3f(static_cast<float>((u + 0.5 - c.cx) / c.fx * z),
               static_cast<float>((v + 0.5 - c.cy) / c.fy * z), static_cast<float>(z));
}

TEST(MaskCheck, CountsTheSeenPointsAndThoseInsideTheMask) {
  // A wall at 1 m; the mask is the left half of the image.
  cv::Mat depth(48, 64, CV_16UC1, cv::Scalar(1000));
  depth(cv::Rect(0, 0, 4, 4)).setTo(cv::Scalar(0));  // a hole
  segmentation::Mask mask;
  mask.width = 64;
  mask.height = 48;
  mask.data.assign(64 * 48, 0);
  for (int v = 0; v < 48; ++v)
    for (int u = 0; u < 32; ++u) mask.data[v * 64 + u] = 1;
  PointCloud points;
  for (int u = 10; u < 50; ++u) points.push_back(point_at(u, 20, 1.0));  // 22 inside, 18 outside
  points.push_back(point_at(20, 30, 1.5));                               // behind the wall
  points.push_back(point_at(20, 30, 1.02));                              // on it, within 3 cm
  points.push_back(point_at(1, 1, 1.0));                                 // in the hole
  points.push_back(Vec3f(5.0f, 0.0f, 1.0f));                             // outside the image
  points.push_back(Vec3f(0.0f, 0.0f, -1.0f));                            // behind the camera
  const MaskViewCount c = count_inside_mask(points, Pose::Identity(), camera(), depth, mask);
  EXPECT_EQ(c.visible, 41u);
  EXPECT_EQ(c.inside, 23u);

  // The camera moved 10 cm to the right: every point moves 5 px left in the image.
  Pose moved = Pose::Identity();
  moved.translate(Vec3(0.1, 0, 0));
  PointCloud row;
  for (int u = 10; u < 50; ++u) row.push_back(point_at(u, 20, 1.0));
  const MaskViewCount m = count_inside_mask(row, moved, camera(), depth, mask);
  EXPECT_EQ(m.visible, 40u);
  EXPECT_EQ(m.inside, 27u);
}

TEST(MaskCheck, BadInputIsNamed) {
  MaskCheckOptions o;
  o.depth_tolerance_m = -1;
  EXPECT_NE(test::error_of([&] { o.check(); }).find("MaskCheckOptions.depth_tolerance_m"),
            std::string::npos);
  test::TempDir dir;
  EXPECT_NE(test::error_of([&] { check_run_masks(dir.path()); }).find("no run.json"),
            std::string::npos);
}

}  // namespace
}  // namespace objmap::pipeline
