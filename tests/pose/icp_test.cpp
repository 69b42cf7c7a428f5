// Point-to-plane ICP of a view against a model whose answer is known.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "objmap/core/error.h"
#include "objmap/pose/icp.h"

namespace objmap::pose {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Three faces of a 20 × 15 × 10 cm box seen from a corner, sampled every 2 mm (the depth pixels of
// a view), with `noise_m` Gaussian noise along each axis.
PointCloud box_corner(double noise_m, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, noise_m);
  PointCloud cloud;
  const double step = 0.002;
  auto add = [&](const Vec3& p) {
    cloud.push_back(Vec3f(static_cast<float>(p.x() + n(rng)), static_cast<float>(p.y() + n(rng)),
                          static_cast<float>(p.z() + n(rng))));
  };
  for (double a = 0; a <= 0.20; a += step)
    for (double b = 0; b <= 0.15; b += step) add(Vec3(a, b, 0.10));  // top
  for (double a = 0; a <= 0.20; a += step)
    for (double c = 0; c <= 0.10; c += step) add(Vec3(a, 0.0, c));  // front
  for (double b = 0; b <= 0.15; b += step)
    for (double c = 0; c <= 0.10; c += step) add(Vec3(0.0, b, c));  // side
  return cloud;
}

PointCloud transformed(const PointCloud& cloud, const Pose& t) {
  PointCloud out;
  for (const Vec3f& p : cloud.points) out.push_back((t * p.cast<double>()).cast<float>());
  return out;
}

Pose small_motion() {
  Pose t = Pose::Identity();
  t.linear() =
      (Eigen::AngleAxisd(3.0 * kPi / 180, Vec3(0.3, 1.0, 0.2).normalized())).toRotationMatrix();
  t.translation() = Vec3(0.012, -0.008, 0.006);
  return t;
}

TEST(Icp, RecoversTheMotionOfANoisyViewOfABoxCorner) {
  const PointCloud model = box_corner(0.001, 1);
  const Pose motion = small_motion();
  // Another scan of the same surfaces (other noise), moved by `motion`: the alignment must undo it.
  const PointCloud view = transformed(box_corner(0.001, 2), motion);
  const ModelAligner aligner(model, IcpOptions{});
  const IcpResult r = aligner.align(view);
  ASSERT_TRUE(r.aligned) << r.inlier_share;
  const Pose residual = r.correction * motion;  // identity when the motion is undone
  EXPECT_LT(residual.translation().norm(), 0.001);
  EXPECT_LT(Eigen::AngleAxisd(residual.linear()).angle() * 180 / kPi, 0.1);
  EXPECT_GT(r.inlier_share, 0.9);
  EXPECT_LT(r.rms_m, 0.002);
  // Three faces pin every direction down: its own uncertainty is small and covers the error.
  EXPECT_LT(r.rotation_sigma_deg, 0.1);
  EXPECT_LT(r.translation_sigma_m, 0.001);
  EXPECT_GT(r.rotation_sigma_deg, 0.0);
}

TEST(Icp, APlaneLeavesItsSlidingDirectionsUncertain) {
  // Three faces vs one: the one face cannot fix the motion along itself, and the alignment says so.
  const PointCloud model = box_corner(0.001, 4), view = box_corner(0.001, 5);
  const auto top = [](const PointCloud& cloud) {
    PointCloud out;
    for (const Vec3f& p : cloud.points)
      if (p.z() > 0.095f) out.push_back(p);
    return out;
  };
  const IcpResult corner = ModelAligner(model, IcpOptions{}).align(view);
  const IcpResult plane = ModelAligner(top(model), IcpOptions{}).align(top(view));
  ASSERT_TRUE(corner.aligned && plane.aligned);
  // PCA normals of noisy points tilt (1 mm noise at 2 mm spacing), which lends a plane some
  // apparent grip along itself: measured 2.0x the corner's std, not orders of magnitude.
  EXPECT_GT(plane.translation_sigma_m, 1.5 * corner.translation_sigma_m)
      << plane.translation_sigma_m << " vs " << corner.translation_sigma_m;
}

TEST(Icp, APlaneIsNotSlidAlongItself) {
  // A flat patch: motion along the plane is not observable; the alignment must fix the offset
  // across the plane and leave the sliding directions alone (no drift along them).
  PointCloud plane;
  for (double a = 0; a <= 0.2; a += 0.002)
    for (double b = 0; b <= 0.2; b += 0.002)
      plane.push_back(Vec3f(static_cast<float>(a), static_cast<float>(b), 0.0f));
  Pose shift = Pose::Identity();
  shift.translation() = Vec3(0.0, 0.0, 0.007);
  const ModelAligner aligner(plane, IcpOptions{});
  const IcpResult r = aligner.align(transformed(plane, shift));
  ASSERT_TRUE(r.aligned);
  EXPECT_NEAR(r.correction.translation().z(), -0.007, 2e-4);
  EXPECT_LT(std::abs(r.correction.translation().x()), 1e-4);
  EXPECT_LT(std::abs(r.correction.translation().y()), 1e-4);
}

TEST(Icp, AViewOfSomethingElseDoesNotAlign) {
  const PointCloud model = box_corner(0.0005, 3);
  Pose far = Pose::Identity();
  far.translation() = Vec3(0.5, 0.0, 0.0);  // beyond the correspondence distance
  const ModelAligner aligner(model, IcpOptions{});
  const IcpResult r = aligner.align(transformed(model, far));
  EXPECT_FALSE(r.aligned);
  EXPECT_LT(r.inlier_share, 0.5);
}

TEST(Icp, TooSmallAModelOrAnEmptyViewDoesNotAlign) {
  PointCloud tiny;
  tiny.push_back(Vec3f(0, 0, 0));
  EXPECT_FALSE(ModelAligner(tiny, IcpOptions{}).align(box_corner(0.0, 1)).aligned);
  EXPECT_FALSE(ModelAligner(box_corner(0.0, 1), IcpOptions{}).align(PointCloud{}).aligned);
}

TEST(Icp, BadOptionsNameTheField) {
  IcpOptions o;
  o.max_correspondence_m = 0.0;
  try {
    o.check();
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("IcpOptions.max_correspondence_m"), std::string::npos);
  }
}

}  // namespace
}  // namespace objmap::pose
