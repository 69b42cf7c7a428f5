#pragma once
// Private to lib/objmap/scene: the up direction and the surfaces on a sample of the dense map
// already taken (pcl_cloud.h), so that find_up_and_surfaces samples the map once.
#include <vector>

#include "objmap/scene/pcl_cloud.h"
#include "objmap/scene/scene.h"

namespace objmap::scene::detail {

// estimate_up with the dense map sampled on options.sample_voxel_m and thinned to
// options.max_sample_points (sample_on_grid); the sample is not used when the mode gives up.
UpEstimate estimate_up(const std::vector<Pose>& cameras, const Cloud::Ptr& sample,
                       const UpOptions& options);

// Each sample point's unit surface normal: the plane (PCA) of the sample points in its grid cell
// and the 26 cells around it (`sample` one point per cell of `cell_m`, as sample_on_grid gives
// it); zero where fewer than 3. PCL's NormalEstimation (k nearest by a kd-tree) gives the same
// on planes at 3x the time (docs/benchmarks.md, "The scene step").
std::vector<Eigen::Vector3f> grid_normals(const Cloud::Ptr& sample, double cell_m);

// find_surfaces with the dense map sampled on options.sample_voxel_m (sample_on_grid, not thinned)
// and the sample's normals (grid_normals(sample, options.sample_voxel_m)).
std::vector<Surface> find_surfaces(const Cloud::Ptr& sample,
                                   const std::vector<Eigen::Vector3f>& normals, const Vec3& up,
                                   const SurfaceOptions& options);

}  // namespace objmap::scene::detail
