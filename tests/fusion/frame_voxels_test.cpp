#include "objmap/fusion/frame_voxels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>

#include "objmap/core/camera.h"
#include "objmap/core/error.h"

namespace objmap::fusion {
namespace {

// A 640x480 fr1 frame: a tilted wall with a box in front of it, rough depth (every pixel up to
// ±noise_mm off), holes, pixels beyond the depth range and a textured colour image.
struct TestFrame {
  cv::Mat depth, bgr;
  Pose world_from_cam = Pose::Identity();
};
TestFrame make_frame(double noise_mm) {
  TestFrame f;
  f.depth = cv::Mat(480, 640, CV_16UC1);
  f.bgr = cv::Mat(480, 640, CV_8UC3);
  std::uint32_t state = 99;
  const auto next = [&] {
    state = state * 1664525u + 1013904223u;
    return static_cast<double>(state >> 8) / static_cast<double>(1u << 24);
  };
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) {
      double z = 1.2 + 0.0015 * u + 0.0004 * v;  // the wall
      if (u > 200 && u < 380 && v > 150 && v < 330) z = 0.8;
      z += noise_mm * 1e-3 * (2 * next() - 1);
      std::uint16_t raw = static_cast<std::uint16_t>(std::lround(z * 5000));
      if ((u * 7 + v * 13) % 97 == 0) raw = 0;  // holes
      if (u > 600 && v < 40) raw = 30000;       // 6 m: beyond max_depth_m
      f.depth.at<std::uint16_t>(v, u) = raw;
      f.bgr.at<cv::Vec3b>(v, u) =
          cv::Vec3b(static_cast<std::uint8_t>(u), static_cast<std::uint8_t>(v),
                    static_cast<std::uint8_t>(u ^ v));
    }
  }
  f.world_from_cam.linear() =
      Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.3, 1.0, 0.2).normalized()).toRotationMatrix();
  f.world_from_cam.translation() = Vec3(0.7, -0.3, 1.1);
  return f;
}

// Every voxel of `a` is in `b` with the same counts and colour sums and (summed in another order)
// nearly the same offset sums.
void expect_same_voxels(const VoxelMap& a, const VoxelMap& b) {
  ASSERT_EQ(a.size(), b.size());
  std::size_t checked = 0;
  a.for_each([&](VoxelKey key, const VoxelData& va) {
    const VoxelData* vb = b.find(key);
    ASSERT_NE(vb, nullptr);
    EXPECT_EQ(va.count, vb->count);
    EXPECT_EQ(va.color_count, vb->color_count);
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(va.color_sum[k], vb->color_sum[k]);
      EXPECT_NEAR(va.offset_sum[k], vb->offset_sum[k], 1e-5 * va.count);
    }
    ++checked;
  });
  EXPECT_EQ(checked, a.size());
}

struct Case {
  std::string name;
  int shards;
  int stride;
  bool colour;
  bool mask;
  cv::Rect roi;
  double noise_mm;
};

// frame_voxels() + add() gives the map that backproject() + insert() gives, for any shard count
// (a power of two or not), stride, region, mask, with and without colours; its point counts are
// backproject()'s.
TEST(FrameVoxels, SameMapAsBackprojectAndInsert) {
  const Camera camera = camera_preset("fr1");
  const geometry::RayTable rays = geometry::make_ray_table(camera);
  Mask mask;
  mask.width = 640;
  mask.height = 480;
  mask.data.assign(640 * 480, 0);
  for (int v = 100; v < 400; ++v)
    for (int u = 50 + v % 7; u < 500; ++u) mask.data[static_cast<std::size_t>(v) * 640 + u] = 1;
  const Case cases[] = {
      {"16 shards", 16, 1, true, false, {}, 2.0},
      {"1 shard", 1, 1, true, false, {}, 2.0},
      {"3 shards, no colour", 3, 1, false, false, {}, 2.0},
      {"stride 2", 16, 2, true, false, {}, 2.0},
      {"stride 3, odd region", 16, 3, true, false, cv::Rect(13, 7, 301, 222), 2.0},
      {"mask", 16, 1, true, true, {}, 2.0},
      {"region cut by the image", 4, 1, true, false, cv::Rect(600, 400, 100, 100), 2.0},
      {"smooth depth", 16, 1, true, false, {}, 0.0},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const TestFrame f = make_frame(c.noise_mm);
    const geometry::DepthFrame frame(f.depth, f.world_from_cam, c.colour ? &f.bgr : nullptr,
                                     c.mask ? &mask : nullptr, c.roi);
    geometry::BackprojectOptions options;
    options.stride = c.stride;
    VoxelMapOptions map_options;
    map_options.shards = c.shards;
    VoxelMap reference(map_options), ours(map_options);
    const auto points = geometry::backproject(rays, frame, options);
    reference.insert(points.points_in_world);

    FrameVoxels voxels;
    frame_voxels(rays, frame, options, ours, voxels);
    ours.add(voxels);
    EXPECT_EQ(voxels.points(), points.points_in_world.size());
    EXPECT_EQ(voxels.dropped(), 0u);
    EXPECT_EQ(voxels.pixels_considered(), points.pixels_considered);
    EXPECT_EQ(ours.points_inserted(), reference.points_inserted());
    expect_same_voxels(reference, ours);
    // A voxel's pixels mostly become one entry; rough depth (a voxel's pixels scattered among
    // others') makes some voxels leave the cache and come back.
    EXPECT_GE(voxels.entries(), ours.size());
    EXPECT_LE(voxels.entries(), c.noise_mm > 0 ? 2 * ours.size() : ours.size() * 21 / 20);
    // Each entry sits in its key's shard.
    for (std::size_t s = 0; s < voxels.shard_count(); ++s)
      for (const auto* e = voxels.shard_begin(s); e != voxels.shard_end(s); ++e)
        EXPECT_EQ(ours.shard_of(e->key), s);
  }
}

// A voxel that leaves the cache and comes back gets a second entry; both add up.
TEST(FrameVoxels, RepeatedVoxelsAddUp) {
  const Camera camera = camera_preset("fr1");
  const geometry::RayTable rays = geometry::make_ray_table(camera);
  const TestFrame f = make_frame(8.0);  // ±8 mm: a voxel's pixels are scattered over 2 cm of depth
  const geometry::DepthFrame frame(f.depth, f.world_from_cam, &f.bgr);
  VoxelMap reference({0.01, 1, 16}), ours({0.01, 1, 16});
  reference.insert(geometry::backproject(rays, frame).points_in_world);
  FrameVoxels voxels;
  frame_voxels(rays, frame, {}, ours, voxels);
  ours.add(voxels);
  EXPECT_GT(voxels.entries(), ours.size() + 1000);
  expect_same_voxels(reference, ours);
  // A second frame of the same view doubles every count.
  frame_voxels(rays, frame, {}, ours, voxels);
  ours.add(voxels);
  reference.for_each([&](VoxelKey key, const VoxelData& v) {
    ASSERT_NE(ours.find(key), nullptr);
    EXPECT_EQ(ours.find(key)->count, 2 * v.count);
  });
}

// Points outside the key range (±10 km at 1 cm) are dropped and counted, as insert() does.
TEST(FrameVoxels, PointsOutOfKeyRangeAreDropped) {
  const Camera camera = camera_preset("fr1");
  const geometry::RayTable rays = geometry::make_ray_table(camera);
  const TestFrame f = make_frame(0.0);
  Pose far = f.world_from_cam;
  far.translation() = Vec3(2e4, 0, 0);  // 20 km away
  VoxelMap map({0.01, 1, 16});
  FrameVoxels voxels;
  frame_voxels(rays, geometry::DepthFrame(f.depth, far, &f.bgr), {}, map, voxels);
  EXPECT_GT(voxels.points(), 200000u);
  EXPECT_EQ(voxels.dropped(), voxels.points());
  EXPECT_EQ(voxels.entries(), 0u);
  map.add(voxels);
  EXPECT_EQ(map.size(), 0u);
  EXPECT_EQ(map.points_dropped(), voxels.points());
}

TEST(FrameVoxels, BadInputIsRefused) {
  const Camera camera = camera_preset("fr1");
  const geometry::RayTable rays = geometry::make_ray_table(camera);
  const cv::Mat small(240, 320, CV_16UC1, cv::Scalar(5000));
  VoxelMap map({0.01, 1, 16});
  FrameVoxels voxels;
  try {
    frame_voxels(rays, geometry::DepthFrame(small, Pose::Identity()), {}, map, voxels);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("image is 320x240; expected the camera's 640x480"),
              std::string::npos)
        << e.what();
  }
  // Voxels made for a map of 16 shards do not go into a map of 4.
  const TestFrame f = make_frame(0.0);
  frame_voxels(rays, geometry::DepthFrame(f.depth, f.world_from_cam), {}, map, voxels);
  VoxelMap other({0.01, 1, 4});
  EXPECT_THROW(other.add(voxels), InputError);
  EXPECT_THROW(map.add_shard(voxels, 16), InputError);
  VoxelMap coarse({0.05, 1, 16});  // made for 1 cm voxels
  EXPECT_THROW(coarse.add(voxels), InputError);
}

}  // namespace
}  // namespace objmap::fusion
