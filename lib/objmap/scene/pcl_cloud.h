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

// The best plane of `cloud` by RANSAC (PCL's SACSegmentation, least-squares refined): its unit
// normal n and offset d (n · p = d for its points) and the inliers. `axis`/`eps_deg` > 0: only
// planes whose normal is within eps_deg of ±axis (SACMODEL_PERPENDICULAR_PLANE). Empty inliers
// when none is found.
struct Plane {
  Vec3 normal = Vec3::UnitZ();
  double offset = 0.0;
  std::vector<int> inliers;
};
Plane fit_plane(const Cloud::Ptr& cloud, double distance_m, const Vec3& axis, double eps_deg);

// `cloud` thinned evenly (every n-th point) to at most `max_output` points; `cloud` itself when it
// has no more.
Cloud::Ptr thin(const Cloud::Ptr& cloud, std::size_t max_output);

// `cloud` without the points at `indices` (sorted ascending).
Cloud::Ptr without(const Cloud::Ptr& cloud, const std::vector<int>& indices);

}  // namespace objmap::scene::detail
