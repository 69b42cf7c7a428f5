// scene::detail::fit_plane (private to lib/objmap/scene) runs PCL's RANSAC with its own inlier
// count; it must find what PCL's SACSegmentation finds, plane for plane and inlier for inlier.
#include <gtest/gtest.h>
#include <pcl/ModelCoefficients.h>
#include <pcl/PointIndices.h>
#include <pcl/sample_consensus/ransac.h>
#include <pcl/sample_consensus/sac_model_plane.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <numeric>
#include <random>

#include "objmap/scene/pcl_cloud.h"

namespace objmap::scene::detail {
namespace {

// PCL's own segmentation, as fit_plane ran it before it counted inliers itself: SACSegmentation's
// segment() with SACMODEL_PLANE, SAC_RANSAC, 200 iterations and optimised coefficients, step for
// step (pcl/segmentation/impl/sac_segmentation.hpp), with PCL's own plane model and RANSAC. Not
// SACSegmentation itself: it makes its model in Debian's PCL, built as C++14, where
// PCL_MAKE_ALIGNED_OPERATOR_NEW gives the model Eigen's operator new (malloc), and objmap's C++17
// code, where that macro is empty, deletes it with the global operator delete (ASan:
// alloc-dealloc-mismatch). Here the model is made and deleted on objmap's side, as in fit_plane.
pcl::PointIndices pcl_segment(const Cloud::Ptr& cloud, double distance_m,
                              pcl::ModelCoefficients& coefficients) {
  const auto model = std::make_shared<pcl::SampleConsensusModelPlane<pcl::PointXYZ>>(cloud);
  pcl::RandomSampleConsensus<pcl::PointXYZ> ransac(model, distance_m);
  ransac.setMaxIterations(200);
  pcl::PointIndices inliers;
  if (!ransac.computeModel(0)) return inliers;
  ransac.getInliers(inliers.indices);
  Eigen::VectorXf found(model->getModelSize());
  ransac.getModelCoefficients(found);
  Eigen::VectorXf refined(model->getModelSize());
  model->optimizeModelCoefficients(inliers.indices, found, refined);
  coefficients.values.assign(refined.data(), refined.data() + refined.size());
  model->selectWithinDistance(refined, distance_m, inliers.indices);
  return inliers;
}

// A room corner as the dense map's sample shows it: a floor, a desk top, two walls, ±1 cm of noise
// and 20 % clutter, with many points near the inlier distance's edge.
Cloud::Ptr corner(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.f, 3.f);
  std::normal_distribution<float> noise(0.f, 0.01f);
  Cloud::Ptr cloud(new Cloud);
  for (int i = 0; i < 12000; ++i) {
    const float a = u(rng), b = u(rng);
    switch (i % 5) {
      case 0:
        cloud->push_back({a, b, noise(rng)});
        break;  // floor
      case 1:
        cloud->push_back({a / 3, b / 3, 0.75f + noise(rng)});
        break;  // desk top
      case 2:
        cloud->push_back({noise(rng), a, b});
        break;  // wall x = 0
      case 3:
        cloud->push_back({a, 0.02f * a + noise(rng), b});
        break;  // wall y ≈ 0
      default:
        cloud->push_back({u(rng), u(rng), u(rng)});
        break;  // clutter
    }
  }
  return cloud;
}

TEST(PlaneRansac, FindsWhatPclsSacSegmentationFindsPlaneAfterPlane) {
  for (unsigned seed : {1u, 2u, 3u}) {
    Cloud::Ptr rest = corner(seed);
    for (int k = 0; k < 5 && rest->size() >= 50; ++k) {
      SCOPED_TRACE("seed " + std::to_string(seed) + ", plane " + std::to_string(k));
      pcl::ModelCoefficients expected_coefficients;
      const pcl::PointIndices expected = pcl_segment(rest, 0.02, expected_coefficients);
      const Plane plane = fit_plane(rest, 0.02);
      ASSERT_EQ(plane.inliers, std::vector<int>(expected.indices.begin(), expected.indices.end()));
      ASSERT_EQ(expected_coefficients.values.size(), 4u);
      const Vec3 n(expected_coefficients.values[0], expected_coefficients.values[1],
                   expected_coefficients.values[2]);
      EXPECT_EQ(plane.normal, n / n.norm());
      EXPECT_EQ(plane.offset, -expected_coefficients.values[3] / n.norm());
      std::vector<int> sorted = plane.inliers;
      std::sort(sorted.begin(), sorted.end());
      rest = without(rest, sorted);
    }
  }
}

// Points a few float steps either side of the inlier distance, where a count that sums the
// products in another order or compares in float would disagree with PCL's.
TEST(PlaneRansac, CountsTheInliersAtTheEdgeAsPclDoes) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-3.f, 3.f);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3f n = Eigen::Vector3f(u(rng), u(rng), u(rng)).normalized();
    const float d = u(rng);
    const double threshold = trial % 2 ? 0.02 : 0.03;
    Cloud::Ptr cloud(new Cloud);
    for (int i = 0; i < 500; ++i) {
      Eigen::Vector3f p(u(rng), u(rng), u(rng));
      p -= (n.dot(p) + d) * n;  // onto the plane
      float off = static_cast<float>(threshold);
      for (int k = i % 7; k > 0; --k) off = std::nextafter(off, (i % 2) ? 1.f : 0.f);
      p += ((i % 3) ? off : -off) * n;
      cloud->push_back({p.x(), p.y(), p.z()});
    }
    std::vector<int> all(cloud->size());
    std::iota(all.begin(), all.end(), 0);
    const Eigen::Vector4f plane(n.x(), n.y(), n.z(), d);
    const pcl::SampleConsensusModelPlane<pcl::PointXYZ> pcl_model(cloud);
    const Eigen::VectorXf coefficients = plane;
    ASSERT_EQ(count_plane_inliers(*cloud, all, plane, threshold),
              pcl_model.countWithinDistance(coefficients, threshold))
        << "trial " << trial;
  }
}

TEST(PlaneRansac, NoPlaneInTooFewPoints) {
  Cloud::Ptr two(new Cloud);
  two->push_back({0.f, 0.f, 0.f});
  two->push_back({1.f, 0.f, 0.f});
  EXPECT_TRUE(fit_plane(two, 0.02).inliers.empty());
}

}  // namespace
}  // namespace objmap::scene::detail
