// ObjectMap::join_parts: two objects of one class that are parts of one instance are joined once
// the up is known (fusion/oversize.h, docs/fusion.md "The extent of one instance").
#include <algorithm>
#include <cmath>
#include <iterator>
#include <map>
#include <optional>

#include "objmap/fusion/object_map_object.h"
#include "objmap/fusion/oversize.h"
#include "objmap/segmentation/class_sizes.h"
#include "objmap/segmentation/coco_classes.h"

namespace objmap::fusion {

std::vector<MergeLink> ObjectMap::join_parts(const Vec3& up,
                                             const segmentation::ClassSizes& sizes) {
  std::vector<MergeLink> made;
  const OversizeOptions& o = options_.oversize;
  if (!o.enabled || !o.join_parts) return made;
  o.check();
  // An object as the rule sees it: its class, size limit, surface and footprint.
  struct PartView {
    Object* object = nullptr;
    std::string cls;
    double limit_m = 0.0;
    std::shared_ptr<const std::vector<Vec3>> surface;  // surface_points
    Footprint box;
    double area = 0.0;  // of the footprint (m²)
    bool confirmed = false;
  };
  const auto share_a_track = [](const Object& a, const Object& b) {
    for (int t : a.track_ids)
      if (b.track_ids.count(t)) return true;
    return false;
  };
  const auto view_of = [&](Object* object) {
    PartView v;
    v.object = object;
    v.cls = segmentation::canonical_class(voted_class(*object));
    const std::optional<segmentation::ClassSize> size = sizes.find(v.cls);
    v.limit_m = size ? size->max_m * (1.0 + o.margin) : 0.0;
    v.surface = surface_points(*object, 0.1);
    v.box = footprint(*v.surface, up, o.percentile);
    v.area = (v.box.hi[0] - v.box.lo[0]) * (v.box.hi[1] - v.box.lo[1]);
    v.confirmed = confirmed(*object);
    return v;
  };
  // The fit of a pair (smaller a, larger b) that may join; none when it may not.
  const auto fit_of = [&](const PartView& a, const PartView& b) -> std::optional<PartsFit> {
    if (!a.object->within(*b.object, o.join_gap_m, options_.voxel_m)) return std::nullopt;
    std::vector<double> shared;
    std::set_intersection(a.object->frames.begin(), a.object->frames.end(),
                          b.object->frames.begin(), b.object->frames.end(),
                          std::back_inserter(shared));
    const std::size_t fewer = std::min(a.object->frames.size(), b.object->frames.size());
    if (shared.size() > options_.merge_max_shared_frames * fewer) return std::nullopt;
    const PartsFit fit = fit_parts(*a.surface, *b.surface, b.box, up, o.percentile, o.join_grow_m);
    if (fit.gap_m > o.join_gap_m || fit.union_extent_m > b.limit_m) return std::nullopt;
    if (fit.inside_share < o.join_min_inside && !share_a_track(*a.object, *b.object) &&
        !(o.join_continuous && continuous_parts(*a.surface, *b.surface, up, o)))
      return std::nullopt;
    return fit;
  };
  // The pairs judged so far, by (a id, b id): after a join only the pairs of the two change.
  std::map<std::pair<int, int>, std::optional<PartsFit>> fits;
  std::vector<PartView> views;
  for (const auto& object : objects_)
    if (object->alive && object->observations > 0) {
      PartView v = view_of(object.get());
      if (v.limit_m > 0.0 && !v.surface->empty()) views.push_back(std::move(v));
    }
  while (true) {
    // The pair (smaller, larger footprint) of one class that fits best: the smallest gap, then the
    // larger share inside; ties: the lower ids.
    std::size_t best_small = 0, best_large = 0;
    std::optional<PartsFit> best;
    for (std::size_t ia = 0; ia < views.size(); ++ia)
      for (std::size_t ib = 0; ib < views.size(); ++ib) {
        const PartView& a = views[ia];
        const PartView& b = views[ib];
        if (ia == ib || a.cls != b.cls || a.area > b.area) continue;
        if (a.area == b.area && a.object->id > b.object->id) continue;
        if (!b.confirmed) continue;  // fragments join an object; they do not make one
        const auto key = std::make_pair(a.object->id, b.object->id);
        auto judged = fits.find(key);
        if (judged == fits.end()) judged = fits.emplace(key, fit_of(a, b)).first;
        if (!judged->second) continue;
        const PartsFit& fit = *judged->second;
        if (best && (fit.gap_m > best->gap_m ||
                     (fit.gap_m == best->gap_m && fit.inside_share <= best->inside_share)))
          continue;
        best = fit;
        best_small = ia;
        best_large = ib;
      }
    if (!best) break;
    Object& large = *views[best_large].object;
    Object& small = *views[best_small].object;
    MergeLink link{large.id, small.id, share_a_track(small, large) ? 1.0 : 0.0,
                   (small.centroid - large.centroid).norm(), best->inside_share};
    link.part = true;
    absorb(large, small, link);
    large.frames_in_view = -1;  // judged again (judge_visibility's only_unjudged)
    made.push_back(link);
    for (auto it = fits.begin(); it != fits.end();) {
      const bool touched = it->first.first == large.id || it->first.second == large.id ||
                           it->first.first == small.id || it->first.second == small.id;
      it = touched ? fits.erase(it) : std::next(it);
    }
    views[best_large] = view_of(&large);
    views.erase(views.begin() + static_cast<std::ptrdiff_t>(best_small));
  }
  if (o.join_under) join_under(up, sizes, made);
  return made;
}

void ObjectMap::join_under(const Vec3& up, const segmentation::ClassSizes& sizes,
                           std::vector<MergeLink>& made) {
  const OversizeOptions& o = options_.oversize;
  const auto volume = [](const Footprint& f) {
    return (f.hi[0] - f.lo[0]) * (f.hi[1] - f.lo[1]) * (f.hi[2] - f.lo[2]);
  };
  for (const auto& candidate : objects_) {
    Object& part = *candidate;
    if (!part.alive || !part.too_wide) continue;
    const std::shared_ptr<const std::vector<Vec3>> below_memo = surface_points(part, 0.1);
    const std::vector<Vec3>& below = *below_memo;
    if (below.empty()) continue;
    const Footprint part_box = footprint(below, up, o.percentile);
    Vec3 middle = Vec3::Zero();
    for (const Vec3& p : below) middle += p;
    middle /= static_cast<double>(below.size());
    const std::string part_class = segmentation::canonical_class(voted_class(part));
    Object* into = nullptr;
    PartsFit best;
    for (const auto& other : objects_) {
      Object& b = *other;
      if (!b.alive || &b == &part || b.too_wide || !confirmed(b) ||
          !part.within(b, o.under_gap_m, options_.voxel_m))
        continue;
      const std::string cls = segmentation::canonical_class(voted_class(b));
      if (cls == part_class) continue;
      const std::shared_ptr<const std::vector<Vec3>> above_memo = surface_points(b, 0.1);
      const std::vector<Vec3>& above = *above_memo;
      const Footprint box = footprint(above, up, o.percentile);
      // Under it: its bottom below the other's, its top no higher than the other's middle.
      if (volume(box) <= volume(part_box) || part_box.lo[2] >= box.lo[2] ||
          part_box.hi[2] > 0.5 * (box.lo[2] + box.hi[2]))
        continue;
      // ... and the other stands on it: its middle under the other's footprint (a stand's foot
      // is wider across than the screen it holds).
      bool centred = true;
      for (int k = 0; k < 2; ++k) {
        const double at = box.axes[k].dot(middle);
        centred = centred && at >= box.lo[k] - o.join_grow_m && at <= box.hi[k] + o.join_grow_m;
      }
      if (!centred) continue;
      const PartsFit fit = fit_parts(below, above, box, up, o.percentile, o.join_grow_m);
      const std::optional<segmentation::ClassSize> size = sizes.find(cls);
      if (fit.gap_m > o.under_gap_m ||
          (size && fit.union_extent_m > size->max_m * (1.0 + o.margin)))
        continue;
      if (into && fit.gap_m >= best.gap_m) continue;
      into = &b;
      best = fit;
    }
    if (!into) continue;
    MergeLink link{into->id, part.id, 0.0, (part.centroid - into->centroid).norm(),
                   best.inside_share};
    link.part = true;
    part.too_wide = false;
    part.histogram.clear();  // no class it was called fits it: its votes do not name the whole
    absorb(*into, part, link);
    into->frames_in_view = -1;  // judged again (judge_visibility's only_unjudged)
    made.push_back(link);
  }
}

}  // namespace objmap::fusion
