// The sample's surface normals from its grid (docs/scene.md, "Surfaces"; the benchmark against
// PCL's NormalEstimation is in docs/benchmarks.md, "The scene step").
#include <Eigen/Eigenvalues>
#include <future>

#include "objmap/geometry/voxel_key.h"
#include "objmap/scene/sampled.h"

namespace objmap::scene::detail {

std::vector<Eigen::Vector3f> grid_normals(const Cloud::Ptr& sample, double cell_m,
                                          const GridFrame& frame) {
  const std::size_t n = sample->size();
  const float inv_cell = 1.0f / static_cast<float>(cell_m);  // as sample_on_grid's
  std::vector<geometry::VoxelKey> keys(n);
  geometry::VoxelHashTable<std::uint32_t> first_in_cell(n);  // index + 1 of the cell's point
  for (std::size_t i = 0; i < n; ++i) {
    keys[i] = geometry::voxel_key(frame.to_grid((*sample)[i].getVector3fMap()), inv_cell);
    if (keys[i] == geometry::kNoVoxel) continue;
    std::uint32_t& slot = first_in_cell[keys[i]];
    if (slot == 0) slot = static_cast<std::uint32_t>(i + 1);
  }
  std::vector<Eigen::Vector3f> normals(n, Eigen::Vector3f::Zero());
  // Each point's normal on its own: the two halves of the sample on two threads.
  const auto normals_of = [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      if (keys[i] == geometry::kNoVoxel) continue;
      // Moments about the point itself (small offsets: float keeps them exact enough).
      const Eigen::Vector3f p = (*sample)[i].getVector3fMap();
      Eigen::Vector3f sum = Eigen::Vector3f::Zero();
      Eigen::Matrix3f squares = Eigen::Matrix3f::Zero();
      int count = 0;
      for (const geometry::VoxelKey offset : geometry::neighbourhood_offsets()) {
        const std::uint32_t* j = first_in_cell.find(keys[i] + offset);
        if (!j) continue;
        const Eigen::Vector3f d = (*sample)[*j - 1].getVector3fMap() - p;
        sum += d;
        squares.noalias() += d * d.transpose();
        ++count;
      }
      if (count < 3) continue;
      const Eigen::Vector3f mean = sum / static_cast<float>(count);
      const Eigen::Matrix3f cov = squares / static_cast<float>(count) - mean * mean.transpose();
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> eig;
      eig.computeDirect(cov);
      const Eigen::Vector3f normal = eig.eigenvectors().col(0);  // the smallest eigenvalue's
      if (normal.allFinite()) normals[i] = normal;
    }
  };
  std::future<void> first_half = std::async(std::launch::async, normals_of, 0, n / 2);
  normals_of(n / 2, n);
  first_half.get();
  return normals;
}

}  // namespace objmap::scene::detail
