#pragma once
// Private to lib/objmap/scene: PCL's types for the plane search (not installed, not public).
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <vector>

#include "objmap/core/types.h"

namespace objmap::scene::detail {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

// Where a sampling grid lies: its axes (rows of grid_from_world) and its origin in the world. The
// world's own axes by default; a frame fixed by the cameras (scene::camera_frame) gives the same
// sample of the same map in any world frame.
struct GridFrame {
  Eigen::Matrix3d grid_from_world = Eigen::Matrix3d::Identity();
  Vec3 origin = Vec3::Zero();
  Eigen::Vector3f to_grid(const Eigen::Vector3f& p) const {
    return (grid_from_world.cast<float>() * (p - origin.cast<float>()));
  }
};

// The points on a grid of `voxel_m` laid in `frame`: one point per occupied cell, the mean of all
// the points in it (the cells and means of PCL's VoxelGrid, by a hash table), in the world
// frame, in the order of the cells' keys (geometry::VoxelKey in the grid frame).
Cloud::Ptr sample_on_grid(const std::vector<Vec3f>& points, double voxel_m,
                          const GridFrame& frame = {});

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
