#pragma once
// Private to lib/objmap/scene: the up direction and the surfaces on a sample of the dense map
// already taken (pcl_cloud.h), so that find_up_and_surfaces samples the map once.
#include <vector>

#include "objmap/scene/pcl_cloud.h"
#include "objmap/scene/scene.h"

namespace objmap::scene::detail {

// The grid frame fixed by the cameras: its z the cameras' prior (the mean of their -y axes), its x
// their mean viewing direction made perpendicular to it, its origin their mean position. The same
// map in another world frame (rotated, moved) has the same sample on it. The world's axes when
// there is no camera.
GridFrame camera_frame(const std::vector<Pose>& cameras);

// estimate_up with the dense map sampled on options.sample_voxel_m in camera_frame(cameras)
// (sample_on_grid) and the sample's normals (grid_normals on that grid); neither is used when the
// mode gives up.
UpEstimate estimate_up(const std::vector<Pose>& cameras, const Cloud::Ptr& sample,
                       const std::vector<Eigen::Vector3f>& normals, const UpOptions& options);

// Each sample point's unit surface normal: the plane (PCA) of the sample points in its grid cell
// and the 26 cells around it (`sample` one point per cell of `cell_m` laid in `frame`, as
// sample_on_grid gives it); zero where fewer than 3. PCL's NormalEstimation (k nearest by a
// kd-tree) gives the same on planes at 3x the time (docs/benchmarks.md, "The scene step").
std::vector<Eigen::Vector3f> grid_normals(const Cloud::Ptr& sample, double cell_m,
                                          const GridFrame& frame = {});

// The clusters of `points` whose members are closer than gap_m to another member (connected
// components), each of at least min_points: each cluster's indices ascending, the clusters largest
// first, exactly as PCL's EuclideanClusterExtraction gives them (cluster tolerance gap_m), found on
// a grid of cells rather than with a kd-tree (6.5x faster on a map sample of 108k points;
// docs/benchmarks.md, "The scene step").
std::vector<std::vector<int>> euclidean_clusters(const std::vector<Vec3f>& points, double gap_m,
                                                 std::size_t min_points);
// The same by PCL's EuclideanClusterExtraction with a kd-tree (what euclidean_clusters falls back
// on for points its grid cannot key: not finite, or beyond its range; the tests' reference).
std::vector<std::vector<int>> pcl_euclidean_clusters(const std::vector<Vec3f>& points, double gap_m,
                                                     std::size_t min_points);

// find_surfaces with the dense map sampled on options.sample_voxel_m (sample_on_grid, not thinned)
// and the sample's normals (grid_normals(sample, options.sample_voxel_m)).
std::vector<Surface> find_surfaces(const Cloud::Ptr& sample,
                                   const std::vector<Eigen::Vector3f>& normals, const Vec3& up,
                                   const SurfaceOptions& options);

}  // namespace objmap::scene::detail
