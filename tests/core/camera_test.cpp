#include "objmap/core/camera.h"

#include <gtest/gtest.h>

#include "objmap/core/error.h"

namespace objmap {
namespace {

TEST(Camera, PresetsCarryTumIntrinsics) {
  const Camera fr1 = camera_preset("fr1");
  EXPECT_DOUBLE_EQ(fr1.fx, 517.3);
  EXPECT_DOUBLE_EQ(fr1.cy, 255.3);
  EXPECT_DOUBLE_EQ(fr1.distortion[4], 1.1633);
  EXPECT_TRUE(fr1.has_distortion());
  const Camera fr3 = camera_preset("freiburg3");
  EXPECT_EQ(fr3.name, "fr3");
  EXPECT_DOUBLE_EQ(fr3.fy, 539.2);
  EXPECT_FALSE(fr3.has_distortion());
  EXPECT_THROW(camera_preset("fr4"), InputError);
}

TEST(Camera, UnprojectInvertsProjectWithDistortion) {
  const Camera cam = camera_preset("fr1");
  for (double u : {5.0, 100.0, 318.6, 600.0, 635.0}) {
    for (double v : {3.0, 255.3, 470.0}) {
      const Vec3 p = cam.unproject(u, v, 2.0);
      EXPECT_DOUBLE_EQ(p.z(), 2.0);
      const Eigen::Vector2d uv = cam.project(p);
      EXPECT_NEAR(uv.x(), u, 1e-6) << u << "," << v;
      EXPECT_NEAR(uv.y(), v, 1e-6) << u << "," << v;
    }
  }
}

TEST(Camera, CheckNamesTheBadField) {
  Camera cam = camera_preset("fr3");
  cam.fx = -1;
  try {
    cam.check("cam.json");
    FAIL() << "no throw";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cam.json"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("fx"), std::string::npos);
  }
}

// undistort_pixel stops when a step returns its input; the result must be the 20 full steps' (the
// iteration of OpenCV's cvUndistortPoints) bit for bit, at every pixel of the distorted presets.
TEST(Camera, UndistortStopsEarlyWithTheSameBits) {
  for (const char* name : {"fr1", "fr2"}) {
    const Camera c = camera_preset(name);
    ASSERT_TRUE(c.has_distortion()) << name;
    const double k1 = c.distortion[0], k2 = c.distortion[1], p1 = c.distortion[2],
                 p2 = c.distortion[3], k3 = c.distortion[4];
    std::size_t differ = 0;
    for (int v = -20; v < c.height + 20; ++v) {
      for (int u = -20; u < c.width + 20; ++u) {
        const double xd = (u - c.cx) / c.fx, yd = (v - c.cy) / c.fy;
        double x = xd, y = yd;
        for (int i = 0; i < 20; ++i) {
          const double r2 = x * x + y * y;
          const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
          const double dx = 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
          const double dy = p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
          x = (xd - dx) / radial;
          y = (yd - dy) / radial;
        }
        const Eigen::Vector2d got = c.undistort_pixel(u, v);
        differ += got.x() != x || got.y() != y;
      }
    }
    EXPECT_EQ(differ, 0u) << name;
  }
}

}  // namespace
}  // namespace objmap
