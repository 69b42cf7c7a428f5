#pragma once
// Private to lib/objmap/scene: PCL's types for the plane search (not installed, not public).
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <vector>

#include "objmap/core/types.h"

namespace objmap::scene::detail {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

// The points on a grid of `voxel_m` (PCL's VoxelGrid: one point per occupied cell, the mean), from
// at most `max_input` of them (an even stride through the input: the dense map's points are
// sorted by voxel, so every n-th is an even thinning).
Cloud::Ptr sample_on_grid(const std::vector<Vec3f>& points, double voxel_m,
                          std::size_t max_input = 600000);

// The best plane of `cloud` by RANSAC (PCL's, as its SACSegmentation runs it: 200 iterations, the
// fixed seed, least-squares refined): its unit normal n and offset d (n · p = d for its points) and
// the inliers, the points within `distance_m`. Empty inliers when none is found.
struct Plane {
  Vec3 normal = Vec3::UnitZ();
  double offset = 0.0;
  std::vector<int> inliers;
};
Plane fit_plane(const Cloud::Ptr& cloud, double distance_m);

// How many of `cloud`'s points at `indices` lie closer than `threshold` to the plane a·x + b·y +
// c·z + d = 0: PCL's SampleConsensusModelPlane::countWithinDistance, point for point, in a loop the
// compiler keeps tight (RANSAC's inner loop: Debian builds PCL for plain x86-64, where that count
// is a per-point dot product of a dynamic-size Eigen vector, 10x slower; docs/benchmarks.md, "The
// scene step"). Same point for point: the products summed in the order of that dot product's SSE
// reduction, (a·x + c·z) + (b·y + d), compared with `threshold` as a double.
std::size_t count_plane_inliers(const Cloud& cloud, const std::vector<int>& indices,
                                const Eigen::Vector4f& plane, double threshold);

// `cloud` thinned evenly (every n-th point) to at most `max_output` points; `cloud` itself when it
// has no more.
Cloud::Ptr thin(const Cloud::Ptr& cloud, std::size_t max_output);

// `cloud` without the points at `indices` (sorted ascending).
Cloud::Ptr without(const Cloud::Ptr& cloud, const std::vector<int>& indices);

}  // namespace objmap::scene::detail
