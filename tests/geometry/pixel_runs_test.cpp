#include "objmap/geometry/pixel_runs.h"

#include <gtest/gtest.h>

#include "objmap/core/error.h"

namespace objmap::geometry {
namespace {

Pose tilted_pose(double yaw_rad, const Vec3& t) {
  Pose p = Pose::Identity();
  p.linear() = Eigen::AngleAxisd(yaw_rad, Vec3::UnitZ()).toRotationMatrix() *
               Eigen::AngleAxisd(0.4, Vec3::UnitX()).toRotationMatrix();
  p.translation() = t;
  return p;
}

// A 640x480 frame: a slanted surface with holes (0), pixels out of range (too far) and colours
// that change per pixel; an instance mask that is a disc with a notch.
struct RunsFrame {
  cv::Mat depth = cv::Mat(480, 640, CV_16UC1);
  cv::Mat bgr = cv::Mat(480, 640, CV_8UC3);
  Mask mask{640, 480, std::vector<std::uint8_t>(640 * 480)};
  RunsFrame() {
    for (int v = 0; v < 480; ++v)
      for (int u = 0; u < 640; ++u) {
        std::uint16_t d = static_cast<std::uint16_t>(6000 + 7 * u + 3 * v);
        if ((u * 7 + v * 13) % 29 == 0) d = 0;         // holes
        if (u > 400 && v > 300 && v < 310) d = 60000;  // beyond max_depth_m
        depth.at<std::uint16_t>(v, u) = d;
        bgr.at<cv::Vec3b>(v, u) = cv::Vec3b(u % 256, v % 256, (u + v) % 256);
        const int du = u - 380, dv = v - 260;
        mask.data[static_cast<std::size_t>(v) * 640 + u] =
            du * du + dv * dv < 120 * 120 && !(du > 0 && std::abs(dv) < 6) ? 1 : 0;
      }
  }
};

void expect_same_points(const PointCloud& a, const PointCloud& b) {
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.colors.size(), b.colors.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.points[i], b.points[i]) << "point " << i;  // bit for bit
    if (!a.colors.empty()) {
      ASSERT_EQ(a.colors[i], b.colors[i]) << "colour " << i;
    }
  }
}

TEST(PixelRuns, GiveBackprojectsPointsBitForBitWithAnyPoseInAThirdOfTheBytes) {
  const RayTable rays = make_ray_table(camera_preset("fr1"));
  const RunsFrame f;
  const Pose old_pose = tilted_pose(0.3, Vec3(1.0, -0.5, 1.2));
  const Pose new_pose = tilted_pose(0.35, Vec3(1.1, -0.45, 1.18));
  for (int stride : {1, 2, 3}) {
    BackprojectOptions options;
    options.stride = stride;
    options.pixel_indices = true;
    const DepthFrame at_old(f.depth, old_pose, &f.bgr, &f.mask, mask_bounds(f.mask));
    const BackprojectResult made = backproject(rays, at_old, options);
    ASSERT_GT(made.points_in_world.size(), 4000u) << "stride " << stride;
    ASSERT_GT(made.pixels_no_depth + made.pixels_out_of_range, 100u);  // gaps inside the runs
    const PixelRuns runs =
        make_pixel_runs(made.pixel_index, f.depth, made.points_in_world.colors, stride);
    EXPECT_EQ(runs.size(), made.points_in_world.size());
    // 15 bytes a point as points and colours; the runs hold 5 a point and 8 a run.
    EXPECT_LT(runs.bytes(), made.points_in_world.size() * 15 / 2) << "stride " << stride;
    expect_same_points(points_from_runs(rays, runs, old_pose), made.points_in_world);
    const DepthFrame at_new(f.depth, new_pose, &f.bgr, &f.mask, mask_bounds(f.mask));
    expect_same_points(points_from_runs(rays, runs, new_pose),
                       backproject(rays, at_new, options).points_in_world);
  }
}

TEST(PixelRuns, WithoutColoursOrPointsAndBadInputs) {
  const RayTable rays = make_ray_table(camera_preset("fr1"));
  const RunsFrame f;
  const PixelRuns none = make_pixel_runs({}, f.depth, {}, 1);
  EXPECT_EQ(points_from_runs(rays, none, Pose::Identity()).size(), 0u);
  // A run ends at a row's end even when the next pixel follows in memory.
  const PixelRuns two = make_pixel_runs({639, 640}, f.depth, {}, 1);
  EXPECT_EQ(two.first.size(), 2u);
  const PointCloud p = points_from_runs(rays, two, Pose::Identity());
  ASSERT_EQ(p.size(), 2u);
  EXPECT_TRUE(p.colors.empty());
  EXPECT_FLOAT_EQ(p.points[1].z(), f.depth.at<std::uint16_t>(1, 0) / 5000.f);
  EXPECT_THROW(make_pixel_runs({640u * 480u}, f.depth, {}, 1), InputError);
  EXPECT_THROW(make_pixel_runs({1, 2}, f.depth, {Rgb{}}, 1), InputError);
  EXPECT_THROW(make_pixel_runs({1}, f.depth, {}, 0), InputError);
  PixelRuns bad = make_pixel_runs({10, 11, 12}, f.depth, {}, 1);
  bad.first[0] = 640u * 480u - 2;  // its three pixels run past the table's end
  EXPECT_THROW(points_from_runs(rays, bad, Pose::Identity()), InputError);
}

}  // namespace
}  // namespace objmap::geometry
