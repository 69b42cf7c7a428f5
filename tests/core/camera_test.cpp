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

}  // namespace
}  // namespace objmap
