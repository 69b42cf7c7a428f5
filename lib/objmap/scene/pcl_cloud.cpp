#include "objmap/scene/pcl_cloud.h"

#include <pcl/ModelCoefficients.h>
#include <pcl/PointIndices.h>
#include <pcl/console/print.h>
#include <pcl/filters/extract_indices.h>
#include <pcl/sample_consensus/ransac.h>
#include <pcl/sample_consensus/sac_model_plane.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>

#include "objmap/geometry/voxel_key.h"

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

Cloud::Ptr sample_on_grid(const std::vector<Vec3f>& points, double voxel_m,
                          const GridFrame& frame) {
  // Every point counts: a sample of a thinned map (every n-th point) moves with the thinning's
  // phase, which a point more or less in the map shifts.
  const float inv_cell = 1.0f / static_cast<float>(voxel_m);  // as VoxelGrid's
  const Eigen::Matrix3f grid_from_world = frame.grid_from_world.cast<float>();
  const Eigen::Vector3f origin = frame.origin.cast<float>();
  struct Cell {
    geometry::VoxelKey key;
    Eigen::Vector3f sum;  // grid frame, relative to the cell's corner
    std::uint32_t count;
  };
  std::vector<Cell> cells;
  // The cells in blocks of 8x8x8 (hashed by block; a cell found directly inside its block): a
  // map's points come in voxel order, so most fall in the block of the point before.
  constexpr int kBlockBits = 3, kBlockMask = (1 << kBlockBits) - 1;
  using Block = std::array<std::uint32_t, 1 << (3 * kBlockBits)>;  // cell index + 1
  std::vector<Block> blocks;
  geometry::VoxelHashTable<std::uint32_t> block_of(points.size() / 512 + 16);  // index + 1
  geometry::VoxelKey last_block = geometry::kNoVoxel;
  Block* block = nullptr;
  for (const Vec3f& p : points) {
    const Eigen::Vector3f g = grid_from_world * (p - origin);
    Eigen::Vector3i ijk;
    Eigen::Vector3f offset;
    if (!geometry::voxel_coords(g, inv_cell, ijk, offset)) continue;
    const geometry::VoxelKey block_key =
        geometry::pack_voxel(ijk.x() >> kBlockBits, ijk.y() >> kBlockBits, ijk.z() >> kBlockBits);
    if (block_key != last_block) {
      std::uint32_t& b = block_of[block_key];
      if (b == 0) {
        blocks.emplace_back();  // value-initialised: every cell 0 (none yet)
        b = static_cast<std::uint32_t>(blocks.size());
      }
      last_block = block_key;
      block = &blocks[b - 1];
    }
    std::uint32_t& slot = (*block)[((ijk.x() & kBlockMask) << (2 * kBlockBits)) |
                                   ((ijk.y() & kBlockMask) << kBlockBits) | (ijk.z() & kBlockMask)];
    if (slot == 0) {
      cells.push_back(
          {geometry::pack_voxel(ijk.x(), ijk.y(), ijk.z()), Eigen::Vector3f::Zero(), 0});
      slot = static_cast<std::uint32_t>(cells.size());
    }
    Cell& c = cells[slot - 1];
    c.sum += offset;
    ++c.count;
  }
  std::sort(cells.begin(), cells.end(), [](const Cell& a, const Cell& b) { return a.key < b.key; });
  Cloud::Ptr sampled(new Cloud);
  sampled->reserve(cells.size());
  const Eigen::Matrix3f world_from_grid = grid_from_world.transpose();
  for (const Cell& c : cells) {
    const Eigen::Vector3f g =
        (geometry::unpack_voxel(c.key).cast<float>() + c.sum / static_cast<float>(c.count)) /
        inv_cell;
    const Eigen::Vector3f w = world_from_grid * g + origin;
    sampled->push_back(pcl::PointXYZ(w.x(), w.y(), w.z()));
  }
  return sampled;
}

Cloud::Ptr thin(const Cloud::Ptr& cloud, std::size_t max_output) {
  if (cloud->size() <= max_output) return cloud;
  const std::size_t stride = (cloud->size() + max_output - 1) / max_output;
  Cloud::Ptr thinned(new Cloud);
  for (std::size_t i = 0; i < cloud->size(); i += stride) thinned->push_back((*cloud)[i]);
  return thinned;
}

std::size_t count_plane_inliers(const Cloud& cloud, const std::vector<int>& indices,
                                const Eigen::Vector4f& plane, double threshold) {
  const float a = plane[0], b = plane[1], c = plane[2], d = plane[3];
  // |s| < threshold (double) for a float s is |s| < the float just above threshold's float
  // rounding when that rounding is below threshold, else |s| < the rounding.
  float limit = static_cast<float>(threshold);
  if (static_cast<double>(limit) < threshold)
    limit = std::nextafter(limit, std::numeric_limits<float>::infinity());
  std::size_t count = 0;
  for (const pcl::index_t i : indices) {
    const pcl::PointXYZ& p = cloud[static_cast<std::size_t>(i)];
    count += std::abs((a * p.x + c * p.z) + (b * p.y + d)) < limit ? 1 : 0;
  }
  return count;
}

namespace {

// PCL's plane model with count_plane_inliers for its inlier count (RANSAC's inner loop).
class CountingPlaneModel : public pcl::SampleConsensusModelPlane<pcl::PointXYZ> {
 public:
  using SampleConsensusModelPlane::SampleConsensusModelPlane;

  std::size_t countWithinDistance(const Eigen::VectorXf& model,
                                  const double threshold) const override {
    if (!isModelValid(model)) return 0;
    return count_plane_inliers(*input_, *indices_, model.head<4>(), threshold);
  }
};

}  // namespace

Plane fit_plane(const Cloud::Ptr& cloud, double distance_m) {
  Plane plane;
  if (cloud->size() < 3) return plane;
  quiet_pcl();
  // As PCL's SACSegmentation (SACMODEL_PLANE, SAC_RANSAC, 200 iterations, coefficients optimised)
  // does it, with the counting model above: the same planes, the same inliers.
  const auto model = std::make_shared<CountingPlaneModel>(cloud);  // fixed seed: the same planes
  pcl::RandomSampleConsensus<pcl::PointXYZ> ransac(model, distance_m);
  ransac.setMaxIterations(200);
  if (!ransac.computeModel()) return plane;
  pcl::Indices inliers;
  ransac.getInliers(inliers);
  Eigen::VectorXf coefficients;
  ransac.getModelCoefficients(coefficients);
  Eigen::VectorXf refined;
  model->optimizeModelCoefficients(inliers, coefficients, refined);
  model->selectWithinDistance(refined, distance_m, inliers);
  if (inliers.empty() || refined.size() != 4) return plane;
  const Vec3 n(refined[0], refined[1], refined[2]);
  const double norm = n.norm();
  if (!(norm > 0.0)) return plane;
  plane.normal = n / norm;
  plane.offset = -refined[3] / norm;
  plane.inliers.assign(inliers.begin(), inliers.end());
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
