// ObjectMap::split_oversize: an object wider than its class allows is cut in two
// (fusion/oversize.h, docs/fusion.md "The extent of one instance").
#include <array>
#include <deque>
#include <numeric>

#include "objmap/fusion/object_map_object.h"
#include "objmap/fusion/split.h"
#include "objmap/segmentation/class_sizes.h"
#include "objmap/segmentation/coco_classes.h"

namespace objmap::fusion {

std::vector<SplitLink> ObjectMap::split_oversize(const Vec3& up,
                                                 const segmentation::ClassSizes& sizes,
                                                 std::vector<ClassRename>* renamed) {
  std::vector<SplitLink> made;
  if (!options_.oversize.enabled) return made;
  options_.oversize.check();
  // Each object with the views to be confirmed, then each part of a cut again (a mask over three
  // chairs is cut twice); an object is cut at most 8 times.
  std::deque<std::pair<std::size_t, int>> todo;
  for (std::size_t i = 0; i < objects_.size(); ++i) {
    objects_[i]->too_wide = false;  // judged again below (a map whose objects grew since)
    if (objects_[i]->alive && confirmation_count(*objects_[i]) >= options_.min_observations)
      todo.emplace_back(i, 0);
  }
  for (; !todo.empty(); todo.pop_front()) {
    const auto [index, depth] = todo.front();
    const std::optional<segmentation::ClassSize> size = sizes.find(voted_class(*objects_[index]));
    if (!size || depth >= 8) continue;
    SplitLink link;
    double one_wide_m = 0.0;
    if (!cut_oversize(index, up, size->min_m, size->max_m, link, &one_wide_m)) {
      Object& o = *objects_[index];
      const std::string to = one_wide_m > 0.0 && options_.oversize.rename
                                 ? name_for_size(o, one_wide_m, sizes)
                                 : std::string();
      if (!to.empty()) {
        if (renamed) renamed->push_back({o.id, voted_class(o), to, one_wide_m});
        o.size_class = to;
      }
      o.too_wide = one_wide_m > 0.0 && to.empty();
      continue;
    }
    todo.emplace_back(index, depth + 1);
    for (int part : link.parts) todo.emplace_back(static_cast<std::size_t>(part), depth + 1);
    made.push_back(std::move(link));
  }
  return made;
}

std::string ObjectMap::name_for_size(const Object& o, double extent_m,
                                     const segmentation::ClassSizes& sizes) const {
  const std::string voted = voted_class(o);
  const auto voted_vote = o.histogram.find(voted);
  if (voted_vote == o.histogram.end()) return {};
  const double bar = options_.oversize.rename_min_vote * voted_vote->second.score_sum;
  const std::string* best = nullptr;
  double best_score = 0.0;
  for (const auto& [name, vote] : o.histogram) {
    if (name == voted || vote.score_sum < bar || (best && vote.score_sum <= best_score)) continue;
    const std::optional<segmentation::ClassSize> size = sizes.find(name);
    if (!size || extent_m > size->max_m * (1.0 + options_.oversize.margin)) continue;
    best = &name;
    best_score = vote.score_sum;
  }
  return best ? *best : std::string();
}

bool ObjectMap::cut_oversize(std::size_t index, const Vec3& up, double min_m, double max_m,
                             SplitLink& link, double* one_wide_m) {
  Object& o = *objects_[index];
  // 1. The cut through its surface (voxels seen in >= 10% of its observations).
  const std::shared_ptr<const std::vector<Vec3>> surface_memo = surface_points(o, 0.1);
  const std::vector<Vec3>& surface = *surface_memo;
  bool tall_beyond = false;
  const std::optional<OversizeCut> cut =
      plan_oversize_cut(surface, up, min_m, max_m, options_.oversize, &tall_beyond);
  if (!cut) return false;
  const auto side = [&](const Vec3& p) { return cut->axis.dot(p) < cut->cut ? 0 : 1; };
  //    One instance with a tall part beyond the cut: trimmed only when that part stands on
  //    another confirmed object of its class (the chair beside it that a mask over both held).
  if (tall_beyond) {
    std::vector<Vec3> beyond;
    for (const Vec3& p : surface)
      if (side(p) != cut->keep) beyond.push_back(p);
    if (!on_another_instance(o, beyond, up)) {
      *one_wide_m = cut->extent_m;
      return false;
    }
  }
  // 2. Two instances: each observation to the side that holds most of its coarse cells (or its
  //    centroid's side); one that holds a quarter of its cells on the other side too (a mask over
  //    both) is taken by both, with its cells on each. One instance with something attached:
  //    every observation to the kept side, and the other side's voxels are no object's.
  const double cell_m = options_.split_cell_voxels * options_.voxel_m;
  const auto cell_side = [&](VoxelKey c) {
    return side((geometry::unpack_voxel(c).cast<double>().array() + 0.5) * cell_m);
  };
  std::vector<int> obs_part(o.provenance.size(), 0);
  std::vector<std::pair<std::size_t, std::vector<VoxelKey>>> shared;  // (observation, other cells)
  for (std::size_t j = 0; j < o.provenance.size(); ++j) {
    std::array<std::vector<VoxelKey>, 2> on;
    if (j < o.cells.size())
      for (VoxelKey c : o.cells[j]) on[cell_side(c)].push_back(c);
    const std::size_t n = on[0].size() + on[1].size();
    if (!cut->apart) {  // one instance: every observation stays with it
      obs_part[j] = cut->keep;
      continue;
    }
    obs_part[j] =
        n > 0 ? (on[1].size() > on[0].size() ? 1 : 0) : side(o.provenance[j].centroid_in_world);
    const int other = 1 - obs_part[j];
    if (n > 0 && on[other].size() * 4 >= n) shared.emplace_back(j, std::move(on[other]));
  }
  // 3. Each voxel to its side. A side without observations is no object: its voxels go with it
  //    and are not confirmed, so no object is wider than its class.
  const auto voxel_part = [&](VoxelKey key) {
    return side((geometry::unpack_voxel(key).cast<double>().array() + 0.5) * options_.voxel_m);
  };
  const std::vector<ObservationLink> links = o.provenance;
  std::vector<std::unique_ptr<Object>> parts = make_parts(o, obs_part, 2, voxel_part);
  for (auto& [j, cells] : shared) parts[1 - obs_part[j]]->take(links[j], std::move(cells));
  for (auto& part : parts) part->sort_provenance();
  link.large_clusters = 0;
  install_parts(index, std::move(parts), link);
  return true;  // `o` is gone from here on
}

bool ObjectMap::on_another_instance(const Object& o, const std::vector<Vec3>& part,
                                    const Vec3& up) const {
  if (part.empty()) return false;
  const std::string cls = segmentation::canonical_class(voted_class(o));
  const OversizeOptions& opt = options_.oversize;
  for (const auto& other : objects_) {
    if (!other->alive || other.get() == &o || !confirmed(*other) ||
        segmentation::canonical_class(voted_class(*other)) != cls)
      continue;
    const std::shared_ptr<const std::vector<Vec3>> surface_memo = surface_points(*other, 0.1);
    const std::vector<Vec3>& surface = *surface_memo;
    const PartsFit fit = fit_parts(part, surface, footprint(surface, up, opt.percentile), up,
                                   opt.percentile, opt.join_grow_m);
    if (fit.inside_share >= 0.5) return true;
  }
  return false;
}

}  // namespace objmap::fusion
