#include "objmap/geometry/backproject.h"

#include <gtest/gtest.h>

#include "objmap/core/error.h"

namespace objmap::geometry {
namespace {

Pose pose(double yaw_rad, const Vec3& t) {
  Pose p = Pose::Identity();
  p.linear() = Eigen::AngleAxisd(yaw_rad, Vec3::UnitY()).toRotationMatrix() *
               Eigen::AngleAxisd(0.3, Vec3::UnitX()).toRotationMatrix();
  p.translation() = t;
  return p;
}

TEST(RayTable, IsTheInverseOfProjectWithFr1Distortion) {
  const Camera camera = camera_preset("fr1");
  const RayTable rays = make_ray_table(camera);
  ASSERT_EQ(rays.x_over_z.size(), 640u * 480u);
  for (int v = 0; v < 480; v += 37) {
    for (int u = 0; u < 640; u += 41) {
      const std::size_t i = static_cast<std::size_t>(v) * 640 + u;
      const Vec3 point_in_cam(rays.x_over_z[i] * 2.0, rays.y_over_z[i] * 2.0, 2.0);
      const Eigen::Vector2d uv = camera.project(point_in_cam);
      EXPECT_NEAR(uv.x(), u, 2e-3) << "pixel " << u << "," << v;
      EXPECT_NEAR(uv.y(), v, 2e-3) << "pixel " << u << "," << v;
    }
  }
  // The distortion matters: at the corner the undistorted ray differs from the pinhole one.
  EXPECT_GT(std::abs(rays.x_over_z[0] - (0 - camera.cx) / camera.fx), 0.01);
}

TEST(Backproject, PlaneAtKnownDepthGivesPointsOnThePlane) {
  const Camera camera = camera_preset("fr1");
  const RayTable rays = make_ray_table(camera);
  cv::Mat depth(480, 640, CV_16UC1, cv::Scalar(7500));  // 1.5 m
  const Pose world_from_cam = pose(0.7, Vec3(1.0, -2.0, 0.5));
  const BackprojectResult r = backproject(rays, DepthFrame(depth, world_from_cam));
  ASSERT_EQ(r.points_in_world.size(), 640u * 480u);
  EXPECT_FALSE(r.points_in_world.has_colors());
  // The plane z_cam = 1.5 in the world: n·p = n·t + 1.5 with n = the camera's z axis.
  const Vec3 n = world_from_cam.linear().col(2);
  const double d = n.dot(world_from_cam.translation()) + 1.5;
  double worst = 0.0;
  for (const Vec3f& p : r.points_in_world.points)
    worst = std::max(worst, std::abs(n.dot(p.cast<double>()) - d));
  EXPECT_LT(worst, 1e-5);
  EXPECT_NEAR(r.centroid_in_cam.z(), 1.5, 1e-9);
  // Pixel (u, v) lands where Camera::unproject says.
  const std::size_t i = 100 * 640 + 200;
  const Vec3 expected = world_from_cam * camera.unproject(200, 100, 1.5);
  EXPECT_LT((r.points_in_world.points[i].cast<double>() - expected).norm(), 1e-5);
}

TEST(Backproject, KeepsOnlyDepthsInRangeAndCountsTheRest) {
  const RayTable rays = make_ray_table(camera_preset("fr3"));
  cv::Mat depth(480, 640, CV_16UC1, cv::Scalar(5000));
  depth.row(0).setTo(0);                  // no depth
  depth.row(1).setTo(cv::Scalar(250));    // 0.05 m: too near
  depth.row(2).setTo(cv::Scalar(25000));  // 5 m: too far
  depth.row(3).setTo(cv::Scalar(500));    // 0.1 m: the bound is kept
  depth.row(4).setTo(cv::Scalar(20000));  // 4.0 m: kept
  const BackprojectResult r = backproject(rays, DepthFrame(depth, Pose::Identity()));
  EXPECT_EQ(r.points_in_world.size(), 640u * 477u);
  EXPECT_EQ(r.pixels_no_depth, 640u);
  EXPECT_EQ(r.pixels_out_of_range, 1280u);
  EXPECT_EQ(r.pixels_considered, 640u * 480u);

  BackprojectOptions paper;
  paper.min_depth_m = 0.01;
  paper.max_depth_m = 6.0;
  EXPECT_EQ(backproject(rays, DepthFrame(depth, Pose::Identity()), paper).points_in_world.size(),
            640u * 479u);
  paper.min_depth_m = 0.0;  // depth 0 stays "no depth"
  EXPECT_EQ(backproject(rays, DepthFrame(depth, Pose::Identity()), paper).points_in_world.size(),
            640u * 479u);
}

TEST(Backproject, MaskColoursStrideAndPixelIndices) {
  const RayTable rays = make_ray_table(camera_preset("fr3"));
  cv::Mat depth(480, 640, CV_16UC1, cv::Scalar(5000));
  cv::Mat bgr(480, 640, CV_8UC3, cv::Scalar(10, 20, 30));  // B G R
  Mask mask;
  mask.width = 640;
  mask.height = 480;
  mask.data.assign(640 * 480, 0);
  for (int v = 100; v < 120; ++v)
    for (int u = 300; u < 350; ++u) mask.data[v * 640 + u] = 1;

  DepthFrame frame(depth, Pose::Identity(), &bgr, &mask);
  BackprojectOptions options;
  options.pixel_indices = true;
  const BackprojectResult r = backproject(rays, frame, options);
  ASSERT_EQ(r.points_in_world.size(), 20u * 50u);
  ASSERT_TRUE(r.points_in_world.has_colors());
  EXPECT_EQ(r.points_in_world.colors[0], (Rgb{30, 20, 10}));
  EXPECT_EQ(r.pixel_index.front(), 100u * 640u + 300u);
  EXPECT_EQ(r.pixel_index.back(), 119u * 640u + 349u);
  EXPECT_EQ(mask_bounds(mask), cv::Rect(300, 100, 50, 20));

  frame.roi = mask_bounds(mask);  // same result, less work
  EXPECT_EQ(backproject(rays, frame).points_in_world.size(), 1000u);

  options.stride = 2;
  EXPECT_EQ(backproject(rays, frame, options).points_in_world.size(), 10u * 25u);
}

TEST(Backproject, RejectsMismatchedImagesAndBadOptions) {
  const RayTable rays = make_ray_table(camera_preset("fr3"));
  cv::Mat small(240, 320, CV_16UC1, cv::Scalar(5000));
  try {
    backproject(rays, DepthFrame(small, Pose::Identity()));
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "backproject: depth: image is 320x240; expected the camera's 640x480");
  }
  cv::Mat depth8(480, 640, CV_8UC1);
  EXPECT_THROW(backproject(rays, DepthFrame(depth8, Pose::Identity())), InputError);
  cv::Mat depth(480, 640, CV_16UC1, cv::Scalar(5000));
  BackprojectOptions bad;
  bad.max_depth_m = 0.05;
  try {
    backproject(rays, DepthFrame(depth, Pose::Identity()), bad);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "BackprojectOptions.max_depth_m");
  }
}

TEST(MaskBounds, EdgesOddWidthAndEmpty) {
  // Width 13: one 8-byte word and a 5-byte tail per row; pixels on the first and last column.
  Mask mask;
  mask.width = 13;
  mask.height = 7;
  mask.data.assign(13 * 7, 0);
  EXPECT_TRUE(mask_bounds(mask).empty());
  mask.data[2 * 13 + 12] = 255;  // (12, 2): in the tail
  EXPECT_EQ(mask_bounds(mask), cv::Rect(12, 2, 1, 1));
  mask.data[5 * 13 + 0] = 1;  // (0, 5)
  mask.data[5 * 13 + 7] = 1;  // (7, 5): last byte of the word
  EXPECT_EQ(mask_bounds(mask), cv::Rect(0, 2, 13, 4));
  mask.data.assign(13 * 7, 0);
  mask.data[6 * 13 + 8] = 1;  // (8, 6): first byte of the tail, last row
  EXPECT_EQ(mask_bounds(mask), cv::Rect(8, 6, 1, 1));
}

}  // namespace
}  // namespace objmap::geometry
