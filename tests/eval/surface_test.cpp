// Surface scores (eval/surface.h) on surfaces whose distances are known: a square and its copies.
#include "objmap/eval/surface.h"

#include <gtest/gtest.h>

namespace objmap::eval {
namespace {

// A square of side `side` m in the plane z = `z`, two triangles.
TriangleMesh square(double side, double z) {
  TriangleMesh m;
  const float s = static_cast<float>(side), h = static_cast<float>(z);
  m.vertices = {{0, 0, h}, {s, 0, h}, {s, s, h}, {0, s, h}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

TEST(Surface, SamplesAreAreaWeightedOnTheMesh) {
  const SurfaceSamples s = sample_mesh(square(0.1, 0.0), 0.001);
  EXPECT_NEAR(static_cast<double>(s.points.size()), 10000.0, 2.0);
  for (const Vec3& p : s.points) {
    EXPECT_NEAR(p.z(), 0.0, 1e-12);
    EXPECT_TRUE(p.x() >= 0 && p.x() <= 0.1 && p.y() >= 0 && p.y() <= 0.1);
  }
}

TEST(Surface, MeshDistanceIsExact) {
  const MeshDistance d(square(0.1, 0.0));
  EXPECT_NEAR(d(Vec3(0.05, 0.05, 0.007)), 0.007, 1e-9);
  EXPECT_NEAR(d(Vec3(0.13, 0.05, 0.04)), 0.05, 1e-9);  // beyond the edge: 3-4-5
}

TEST(Surface, ScoresOfAShiftedCopyFollowTheShift) {
  const TriangleMesh truth = square(0.1, 0.0);
  const MeshDistance distance(truth);
  const std::vector<Vec3> seen = sample_mesh(truth, 0.002).points;
  SurfaceEvalOptions options;
  const SurfaceScores near =
      score_surface(sample_mesh(square(0.1, 0.005), 0.001).points, distance, seen, options);
  EXPECT_NEAR(near.accuracy_mean_m, 0.005, 1e-6);
  EXPECT_NEAR(near.accuracy_p90_m, 0.005, 1e-6);
  EXPECT_DOUBLE_EQ(near.completeness, 1.0);
  EXPECT_DOUBLE_EQ(near.fscore, 1.0);
  const SurfaceScores far =
      score_surface(sample_mesh(square(0.1, 0.02), 0.001).points, distance, seen, options);
  EXPECT_NEAR(far.accuracy_mean_m, 0.02, 1e-6);
  EXPECT_DOUBLE_EQ(far.completeness, 0.0);
  EXPECT_DOUBLE_EQ(far.fscore, 0.0);
  // Half the square: the other half of the truth is missing.
  const SurfaceScores half =
      score_surface(sample_mesh(square(0.05, 0.0), 0.001).points, distance, seen, options);
  EXPECT_NEAR(half.completeness, 0.25 + 0.25 * 0.4, 0.05);  // 0.05 m square + 1 cm band around it
  EXPECT_DOUBLE_EQ(half.precision, 1.0);
}

TEST(Surface, OnlySamplesFacingTheCameraWithAgreeingDepthAreSeen) {
  SurfaceSamples truth;
  truth.points = {Vec3(0, 0, 1), Vec3(0, 0, 1), Vec3(0, 0, 2)};
  truth.normals = {Vec3(0, 0, -1), Vec3(0, 0, 1), Vec3(0, 0, -1)};  // the second faces away
  DepthImage view;
  view.camera.width = 640;
  view.camera.height = 480;
  view.camera.depth_factor = 1000.0;
  view.depth = cv::Mat(480, 640, CV_16UC1, cv::Scalar(1000));  // everything at 1 m
  const std::vector<bool> seen = seen_samples(truth, {view}, SurfaceEvalOptions{});
  EXPECT_TRUE(seen[0]);
  EXPECT_FALSE(seen[1]);
  EXPECT_FALSE(seen[2]);  // behind the measured surface: hidden
}

}  // namespace
}  // namespace objmap::eval
