// ObjectMap::split_pass: an object whose surface forms clusters its observations see apart is
// split (fusion/split.h); the parts replace it (also for split_oversize).
#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <iterator>
#include <limits>
#include <set>
#include <string>

#include "objmap/core/error.h"
#include "objmap/fusion/object_map_object.h"
#include "objmap/fusion/palette.h"
#include "objmap/fusion/split.h"
#include "objmap/geometry/bounds.h"
#include "objmap/segmentation/coco_classes.h"

namespace objmap::fusion {

std::vector<SplitLink> ObjectMap::split_pass() {
  std::vector<SplitLink> made;
  if (!options_.split_clusters) return made;
  const std::size_t n = objects_.size();  // the parts made are not split again
  for (std::size_t i = 0; i < n; ++i) {
    SplitLink link;
    if (objects_[i]->alive && split_object(i, link)) made.push_back(std::move(link));
  }
  return made;
}

bool ObjectMap::split_object(std::size_t index, SplitLink& link) {
  Object& o = *objects_[index];
  if (o.cells.size() != o.provenance.size() || o.provenance.size() < 2) return false;
  const int cv = options_.split_cell_voxels;
  // 1. The surface (voxels seen in >= 10% of its observations, as the visibility sample) per
  //    coarse cell, and the cells of all its voxels.
  const double need = std::min(255.0, std::max(1.0, 0.1 * o.observations));
  std::vector<VoxelKey> surface, all;
  o.voxels->for_each([&](VoxelKey key, const VoxelData&) {
    const VoxelKey cell = coarse_cell(key, cv);
    all.push_back(cell);
    const std::uint8_t* hits = o.near->find(key);
    if (hits && *hits >= need) surface.push_back(cell);
  });
  std::sort(surface.begin(), surface.end());
  std::vector<VoxelKey> cells;
  std::vector<std::size_t> weight;  // surface voxels per cell
  for (VoxelKey c : surface) {
    if (cells.empty() || cells.back() != c) {
      cells.push_back(c);
      weight.push_back(0);
    }
    ++weight.back();
  }
  // 2. Its clusters, and which of them its observations see apart.
  std::vector<const std::vector<VoxelKey>*> observed;
  for (const auto& c : o.cells) observed.push_back(&c);
  const SplitPlan plan = plan_split(
      cells, weight, observed,
      SplitRules{options_.split_min_share, options_.split_cover_share, options_.split_max_joint});
  if (plan.groups < 2) return false;
  // 3. Each observation to its part (none of its cells on the surface: the nearest part's
  //    centre); every part must have the views to be confirmed, or nothing is split.
  const double cell_m = cv * options_.voxel_m;
  std::vector<Vec3> centre(plan.groups, Vec3::Zero());
  std::vector<double> mass(plan.groups, 0.0);
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const Vec3 at = (geometry::unpack_voxel(cells[i]).cast<double>().array() + 0.5) * cell_m;
    centre[plan.cell_group[i]] += weight[i] * at;
    mass[plan.cell_group[i]] += weight[i];
  }
  for (int g = 0; g < plan.groups; ++g) centre[g] /= mass[g];
  const auto nearest_part = [&](const Vec3& p) {
    int best = 0;
    for (int g = 1; g < plan.groups; ++g)
      if ((p - centre[g]).squaredNorm() < (p - centre[best]).squaredNorm()) best = g;
    return best;
  };
  std::vector<int> obs_part = plan.observation_group;
  std::vector<std::vector<ObservationLink>> part_links(plan.groups);
  for (std::size_t j = 0; j < obs_part.size(); ++j) {
    if (obs_part[j] < 0) obs_part[j] = nearest_part(o.provenance[j].centroid_in_world);
    part_links[obs_part[j]].push_back(o.provenance[j]);
  }
  for (const auto& links : part_links)
    if (count_views(links, options_) < options_.min_observations) return false;
  // 4. Each voxel to the part of its cell: a surface cell's part, else that of the nearest surface
  //    cell through the object's cells (breadth first), else the nearest part's centre.
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  std::vector<int> all_part(all.size(), -1);
  std::deque<std::size_t> todo;
  for (std::size_t i = 0, k = 0; i < all.size(); ++i) {
    while (k < cells.size() && cells[k] < all[i]) ++k;
    if (k < cells.size() && cells[k] == all[i]) {
      all_part[i] = plan.cell_group[k];
      todo.push_back(i);
    }
  }
  const auto& offsets = geometry::neighbourhood_offsets();
  for (; !todo.empty(); todo.pop_front())
    for (VoxelKey off : offsets) {
      const auto it = std::lower_bound(all.begin(), all.end(), all[todo.front()] + off);
      if (it == all.end() || *it != all[todo.front()] + off) continue;
      const std::size_t j = static_cast<std::size_t>(it - all.begin());
      if (all_part[j] >= 0) continue;
      all_part[j] = all_part[todo.front()];
      todo.push_back(j);
    }
  for (std::size_t i = 0; i < all.size(); ++i)
    if (all_part[i] < 0)
      all_part[i] =
          nearest_part((geometry::unpack_voxel(all[i]).cast<double>().array() + 0.5) * cell_m);
  const auto voxel_part = [&](VoxelKey key) {
    const VoxelKey cell = coarse_cell(key, cv);
    const auto it = std::lower_bound(all.begin(), all.end(), cell);
    return it != all.end() && *it == cell ? all_part[it - all.begin()] : 0;
  };
  // 5. The parts: the one with most observations keeps the id (and the merges), the others are
  //    new objects.
  link.large_clusters = plan.large_clusters;
  install_parts(index, make_parts(o, obs_part, plan.groups, voxel_part), link);
  return true;  // `o` is gone from here on
}

void ObjectMap::install_parts(std::size_t index, std::vector<std::unique_ptr<Object>> parts,
                              SplitLink& link) {
  Object& o = *objects_[index];
  const int n = static_cast<int>(parts.size());
  int keep = 0;
  for (int g = 1; g < n; ++g)
    if (parts[g]->observations > parts[keep]->observations) keep = g;
  link.from = o.id;
  parts[keep]->id = o.id;
  parts[keep]->merges = std::move(o.merges);
  parts[keep]->moved = std::move(o.moved);  // an earlier split's moves stay valid
  for (int g = 0; g < n; ++g) {
    if (g == keep) continue;
    parts[g]->id = static_cast<int>(objects_.size());
    link.parts.push_back(parts[g]->id);
    // An observation that both parts took (a mask over both) stays with the kept part.
    for (const ObservationLink& l : parts[g]->provenance)
      if (!parts[keep]->has_frame(l.timestamp))
        parts[keep]->moved.emplace_back(l.timestamp, parts[g]->id);
    objects_.push_back(std::move(parts[g]));
  }
  std::sort(parts[keep]->moved.begin(), parts[keep]->moved.end());
  objects_[index] = std::move(parts[keep]);
}

std::vector<std::unique_ptr<ObjectMap::Object>> ObjectMap::make_parts(
    Object& o, const std::vector<int>& obs_part, int n,
    const std::function<int(VoxelKey)>& voxel_part) {
  std::vector<std::unique_ptr<Object>> parts;
  for (int g = 0; g < n; ++g) {
    auto p = std::make_unique<Object>(options_.voxel_m);
    p->voxels = o.voxels->subset([&](VoxelKey key) { return voxel_part(key) == g; });
    // `near`: each voxel's hits as they were (the observations that had it), its neighbourhood.
    std::vector<VoxelKey> keys;
    p->voxels->for_each([&](VoxelKey key, const VoxelData&) { keys.push_back(key); });
    auto& near = p->near.write();
    for (VoxelKey key : keys) {
      const std::uint8_t* hits = o.near->find(key);
      near[key] = hits ? std::max<std::uint8_t>(1, *hits) : 1;
    }
    p->dilate(keys);
    p->refresh();
    parts.push_back(std::move(p));
  }
  // Its observations: provenance, cells, votes, track ids, frames.
  for (std::size_t j = 0; j < o.provenance.size(); ++j)
    parts[obs_part[j]]->take(o.provenance[j],
                             j < o.cells.size() ? std::move(o.cells[j]) : std::vector<VoxelKey>{});
  // The kept points (keep_points) by their voxel.
  const bool colours = o.points.colors.size() == o.points.points.size();
  for (std::size_t i = 0; i < o.points.size(); ++i) {
    const VoxelKey key = o.voxels->key_of(o.points.points[i]);
    PointCloud& to = parts[key == geometry::kNoVoxel ? 0 : voxel_part(key)]->points;
    to.points.push_back(o.points.points[i]);
    if (colours) to.colors.push_back(o.points.colors[i]);
  }
  return parts;
}

}  // namespace objmap::fusion
