#pragma once
#include <cstddef>
#include <vector>

#include "objmap/geometry/voxel_key.h"

// Splitting an object whose surface forms separate clusters (ObjectMapOptions::split_clusters):
// objects of one class side by side (chairs round a table) that a tracker's ID swaps joined. The
// geometry alone cannot tell two chairs from one chair whose thin legs are a cluster apart from
// its seat; the observations can: one chair's mask covers its seat and its legs in the same
// keyframe, while two chairs are seen one per observation (each observation's cells lie in one
// cluster). Everything here works on coarse cells: voxel keys at cell_voxels × the map's voxel.
namespace objmap::fusion {

using geometry::VoxelKey;

// The cell (of `cell_voxels` voxels a side) holding voxel `voxel`, as a voxel key of the cells.
VoxelKey coarse_cell(VoxelKey voxel, int cell_voxels);

// The distinct cells of `voxels` (keys at the map's voxel), sorted.
std::vector<VoxelKey> coarse_cells(std::vector<VoxelKey> voxels, int cell_voxels);

// Connected components of `cells` (sorted, distinct) in the 26-neighbourhood: one label per cell,
// labels numbered in the order of their first cell. Two cells of different labels are at least
// one cell apart.
std::vector<int> connected_cells(const std::vector<VoxelKey>& cells);

struct SplitRules {
  double min_share = 0.2;    // a cluster is large with at least this share of the weight
  double cover_share = 0.1;  // an observation covers a cluster with this share of its cells on it
  double max_joint = 0.2;    // two large clusters are two objects when at most this share of the
                             // observations covering the less covered one cover both
};

// The parts an object falls into. Empty `cell_group`: one object (no split).
struct SplitPlan {
  std::vector<int> cell_group;         // per cell of the input, its part (0, 1, ...)
  std::vector<int> observation_group;  // per observation, its part; -1: none of its cells on one
  int groups = 0;
  std::size_t large_clusters = 0;  // clusters with min_share of the weight
};

// The plan for an object: `cells` (sorted, distinct) its surface cells, `weight` each cell's
// surface voxels, `observations` each observation's cells (sorted, distinct). Large clusters that
// observations cover together (more than max_joint of the less covered one's) are one part; the
// small clusters go to the part of the nearest large cluster; each observation goes to the part
// that holds most of its cells (ties: the lower part).
SplitPlan plan_split(const std::vector<VoxelKey>& cells, const std::vector<std::size_t>& weight,
                     const std::vector<const std::vector<VoxelKey>*>& observations,
                     const SplitRules& rules);

}  // namespace objmap::fusion
