#include "objmap/fusion/split.h"

#include <algorithm>
#include <cstdint>
#include <deque>
#include <limits>
#include <numeric>

namespace objmap::fusion {

namespace {

int floor_div(int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// Union-find over the large clusters.
int find_root(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// Index of `cell` in the sorted `cells`, or -1.
int cell_index(const std::vector<VoxelKey>& cells, VoxelKey cell) {
  const auto it = std::lower_bound(cells.begin(), cells.end(), cell);
  return it != cells.end() && *it == cell ? static_cast<int>(it - cells.begin()) : -1;
}

// The large clusters (index into `large`) that observations cover together: per pair, joined
// when more than max_joint of the less covered one's observations cover both; the roots of a
// union-find over `large`.
std::vector<int> join_covered_together(
    const std::vector<VoxelKey>& cells, const std::vector<int>& labels,
    const std::vector<int>& large_of_label, std::size_t large,
    const std::vector<const std::vector<VoxelKey>*>& observations, const SplitRules& rules) {
  std::vector<int> covering(large, 0);      // observations covering each
  std::vector<int> both(large * large, 0);  // observations covering each pair
  std::vector<int> count(large);
  for (const std::vector<VoxelKey>* obs : observations) {
    std::fill(count.begin(), count.end(), 0);
    int mapped = 0;  // its cells on the object's surface
    for (VoxelKey c : *obs) {
      const int i = cell_index(cells, c);
      if (i < 0) continue;
      ++mapped;
      const int k = large_of_label[labels[i]];
      if (k >= 0) ++count[k];
    }
    std::vector<std::size_t> covered;
    for (std::size_t k = 0; k < large; ++k)
      if (count[k] > 0 && count[k] >= rules.cover_share * mapped) covered.push_back(k);
    for (std::size_t a : covered) {
      ++covering[a];
      for (std::size_t b : covered) both[a * large + b] += a != b;
    }
  }
  std::vector<int> parent(large);
  std::iota(parent.begin(), parent.end(), 0);
  for (std::size_t a = 0; a < large; ++a)
    for (std::size_t b = a + 1; b < large; ++b) {
      const int fewer = std::min(covering[a], covering[b]);
      // A cluster that no observation covers says nothing: it stays with the others.
      if (fewer == 0 || both[a * large + b] > rules.max_joint * fewer)
        parent[find_root(parent, static_cast<int>(b))] = find_root(parent, static_cast<int>(a));
    }
  for (std::size_t k = 0; k < large; ++k) parent[k] = find_root(parent, static_cast<int>(k));
  return parent;
}

}  // namespace

VoxelKey coarse_cell(VoxelKey voxel, int cell_voxels) {
  const Eigen::Vector3i ijk = geometry::unpack_voxel(voxel);
  return geometry::pack_voxel(floor_div(ijk.x(), cell_voxels), floor_div(ijk.y(), cell_voxels),
                              floor_div(ijk.z(), cell_voxels));
}

std::vector<VoxelKey> coarse_cells(std::vector<VoxelKey> voxels, int cell_voxels) {
  for (VoxelKey& k : voxels) k = coarse_cell(k, cell_voxels);
  std::sort(voxels.begin(), voxels.end());
  voxels.erase(std::unique(voxels.begin(), voxels.end()), voxels.end());
  voxels.shrink_to_fit();  // kept per observation: a cell per 16-64 voxels
  return voxels;
}

std::vector<int> connected_cells(const std::vector<VoxelKey>& cells) {
  const auto& offsets = geometry::neighbourhood_offsets();
  std::vector<int> label(cells.size(), -1);
  int labels = 0;
  std::deque<std::size_t> todo;
  for (std::size_t seed = 0; seed < cells.size(); ++seed) {
    if (label[seed] >= 0) continue;
    label[seed] = labels;
    todo.push_back(seed);
    while (!todo.empty()) {
      const VoxelKey key = cells[todo.front()];
      todo.pop_front();
      for (VoxelKey off : offsets) {
        const int j = cell_index(cells, key + off);
        if (j >= 0 && label[j] < 0) {
          label[j] = labels;
          todo.push_back(static_cast<std::size_t>(j));
        }
      }
    }
    ++labels;
  }
  return label;
}

SplitPlan plan_split(const std::vector<VoxelKey>& cells, const std::vector<std::size_t>& weight,
                     const std::vector<const std::vector<VoxelKey>*>& observations,
                     const SplitRules& rules) {
  SplitPlan plan;
  const std::vector<int> labels = connected_cells(cells);
  const int n_labels = labels.empty() ? 0 : *std::max_element(labels.begin(), labels.end()) + 1;
  std::vector<double> label_weight(n_labels, 0.0);
  for (std::size_t i = 0; i < cells.size(); ++i) label_weight[labels[i]] += weight[i];
  const double total = std::accumulate(label_weight.begin(), label_weight.end(), 0.0);
  std::vector<int> large_of_label(n_labels, -1);
  std::vector<int> large_labels;
  for (int l = 0; l < n_labels; ++l)
    if (label_weight[l] >= rules.min_share * total) {
      large_of_label[l] = static_cast<int>(large_labels.size());
      large_labels.push_back(l);
    }
  plan.large_clusters = large_labels.size();
  if (large_labels.size() < 2) return plan;
  const std::vector<int> root = join_covered_together(cells, labels, large_of_label,
                                                      large_labels.size(), observations, rules);
  // Parts numbered in the order of their first large cluster.
  std::vector<int> part_of_root(large_labels.size(), -1);
  std::vector<int> label_group(n_labels, -1);
  for (std::size_t k = 0; k < large_labels.size(); ++k) {
    int& part = part_of_root[root[k]];
    if (part < 0) part = plan.groups++;
    label_group[large_labels[k]] = part;
  }
  if (plan.groups < 2) {
    plan.groups = 0;
    return plan;
  }
  // Each small cluster joins the part of the large cluster nearest to its mean cell.
  std::vector<Eigen::Vector3d> mean(n_labels, Eigen::Vector3d::Zero());
  std::vector<int> cells_of(n_labels, 0);
  for (std::size_t i = 0; i < cells.size(); ++i) {
    mean[labels[i]] += geometry::unpack_voxel(cells[i]).cast<double>();
    ++cells_of[labels[i]];
  }
  for (int l = 0; l < n_labels; ++l) {
    if (label_group[l] >= 0) continue;
    const Eigen::Vector3d m = mean[l] / cells_of[l];
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < cells.size(); ++i) {
      if (large_of_label[labels[i]] < 0) continue;
      const double d = (geometry::unpack_voxel(cells[i]).cast<double>() - m).squaredNorm();
      if (d < best) {
        best = d;
        label_group[l] = label_group[labels[i]];
      }
    }
  }
  plan.cell_group.resize(cells.size());
  for (std::size_t i = 0; i < cells.size(); ++i) plan.cell_group[i] = label_group[labels[i]];
  // Each observation: the part holding most of its cells.
  std::vector<int> count(static_cast<std::size_t>(plan.groups));
  for (const std::vector<VoxelKey>* obs : observations) {
    std::fill(count.begin(), count.end(), 0);
    for (VoxelKey c : *obs) {
      const int i = cell_index(cells, c);
      if (i >= 0) ++count[plan.cell_group[i]];
    }
    const auto most = std::max_element(count.begin(), count.end());
    plan.observation_group.push_back(*most > 0 ? static_cast<int>(most - count.begin()) : -1);
  }
  return plan;
}

}  // namespace objmap::fusion
