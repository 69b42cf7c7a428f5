#include "objmap/scene/pcl_cloud.h"

#include <pcl/ModelCoefficients.h>
#include <pcl/PointIndices.h>
#include <pcl/console/print.h>
#include <pcl/filters/extract_indices.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <cmath>

namespace objmap::scene::detail {

namespace {
// PCL prints to stderr when RANSAC finds no plane (an outcome objmap handles, not an error).
void quiet_pcl() {
  static const bool once = [] {
    pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
    return true;
  }();
  (void)once;
}
}  // namespace

Cloud::Ptr sample_on_grid(const std::vector<Vec3f>& points, double voxel_m, std::size_t max_input) {
  quiet_pcl();
  Cloud::Ptr all(new Cloud);
  const std::size_t in_stride =
      std::max<std::size_t>(1, (points.size() + max_input - 1) / max_input);
  all->reserve(points.size() / in_stride + 1);
  for (std::size_t i = 0; i < points.size(); i += in_stride)
    all->push_back(pcl::PointXYZ(points[i].x(), points[i].y(), points[i].z()));
  Cloud::Ptr sampled(new Cloud);
  if (all->empty()) return sampled;
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setInputCloud(all);
  const float leaf = static_cast<float>(voxel_m);
  grid.setLeafSize(leaf, leaf, leaf);
  grid.filter(*sampled);
  return sampled;
}

Cloud::Ptr thin(const Cloud::Ptr& cloud, std::size_t max_output) {
  if (cloud->size() <= max_output) return cloud;
  const std::size_t stride = (cloud->size() + max_output - 1) / max_output;
  Cloud::Ptr thinned(new Cloud);
  for (std::size_t i = 0; i < cloud->size(); i += stride) thinned->push_back((*cloud)[i]);
  return thinned;
}

Plane fit_plane(const Cloud::Ptr& cloud, double distance_m, const Vec3& axis, double eps_deg) {
  Plane plane;
  if (cloud->size() < 3) return plane;
  pcl::SACSegmentation<pcl::PointXYZ> seg;  // fixed seed: the same planes on every run
  seg.setOptimizeCoefficients(true);
  seg.setMethodType(pcl::SAC_RANSAC);
  seg.setMaxIterations(200);
  seg.setDistanceThreshold(distance_m);
  if (eps_deg > 0.0) {
    seg.setModelType(pcl::SACMODEL_PERPENDICULAR_PLANE);
    seg.setAxis(axis.cast<float>());
    seg.setEpsAngle(eps_deg * M_PI / 180.0);
  } else {
    seg.setModelType(pcl::SACMODEL_PLANE);
  }
  seg.setInputCloud(cloud);
  pcl::PointIndices inliers;
  pcl::ModelCoefficients coefficients;
  seg.segment(inliers, coefficients);
  if (inliers.indices.empty() || coefficients.values.size() != 4) return plane;
  const Vec3 n(coefficients.values[0], coefficients.values[1], coefficients.values[2]);
  const double norm = n.norm();
  if (!(norm > 0.0)) return plane;
  plane.normal = n / norm;
  plane.offset = -coefficients.values[3] / norm;
  plane.inliers = std::move(inliers.indices);
  return plane;
}

Cloud::Ptr without(const Cloud::Ptr& cloud, const std::vector<int>& indices) {
  pcl::PointIndices::Ptr remove(new pcl::PointIndices);
  remove->indices = indices;
  pcl::ExtractIndices<pcl::PointXYZ> extract;
  extract.setInputCloud(cloud);
  extract.setIndices(remove);
  extract.setNegative(true);
  Cloud::Ptr rest(new Cloud);
  extract.filter(*rest);
  return rest;
}

}  // namespace objmap::scene::detail
