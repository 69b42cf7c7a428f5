// ObjectMap's merge passes (ID-switch repair, class confusions, fragments in a box) and their
// verdicts (fusion/object_map.h, docs/fusion.md "Merge pass").
#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <iterator>
#include <limits>
#include <optional>
#include <set>
#include <string>

#include "objmap/core/error.h"
#include "objmap/fusion/object_map_object.h"
#include "objmap/fusion/palette.h"
#include "objmap/fusion/record_cache.h"
#include "objmap/fusion/split.h"
#include "objmap/geometry/bounds.h"
#include "objmap/segmentation/coco_classes.h"

namespace objmap::fusion {

namespace {
// Timestamps (ascending, unique) of the observations of `o` whose class is `canonical`.
template <typename ObjectT>
std::vector<double> class_frames(const ObjectT& o, const std::string& canonical) {
  std::vector<double> t;
  for (const ObservationLink& l : o.provenance)
    if (segmentation::canonical_class(l.class_name) == canonical) t.push_back(l.timestamp);
  std::sort(t.begin(), t.end());
  t.erase(std::unique(t.begin(), t.end()), t.end());
  return t;
}
}  // namespace

std::uint64_t ObjectMap::pair_content(const Object& o) {
  // Made once per content (the memo; its copies share it).
  ObjectMemo& memo = *o.memo;
  {
    const std::lock_guard<std::mutex> lock(memo.mutex);
    if (memo.pair_content) return *memo.pair_content;
  }
  // Order-free over the voxels and the dilated support table; in order over the rest.
  OrderFreeHash voxels, near;
  o.voxels->for_each([&](VoxelKey key, const VoxelData& v) { voxels.add(voxel_content(key, v)); });
  o.near->for_each(
      [&](VoxelKey key, std::uint8_t hits) { near.add(content_mix(content_mix(key) ^ hits)); });
  std::uint64_t h = voxels.value(o.voxels->size());
  const auto add = [&h](std::uint64_t field) { h = content_mix(h ^ field); };
  add(near.value(o.near->size()));
  for (int k = 0; k < 3; ++k) {
    add(content_bits(o.centroid[k]));
    add(content_bits(o.lo[k]) ^ (content_bits(o.hi[k]) << 32));
  }
  add(content_bits(o.radius));
  add(content_bits(o.observations));
  for (const auto& [name, vote] : o.histogram) {
    add(std::hash<std::string>{}(name));
    add(content_bits(vote.score_sum));
    add(content_bits(vote.count));
  }
  for (const ObservationLink& l : o.provenance) {
    add(content_bits(l.timestamp));
    add(std::hash<std::string>{}(l.class_name));
    add(l.track_id ? content_bits(*l.track_id) + 1 : 0);
  }
  for (double t : o.frames) add(content_bits(t));
  for (int t : o.track_ids) add(content_bits(t));
  const std::lock_guard<std::mutex> lock(memo.mutex);
  memo.pair_content = h;
  return h;
}

void ObjectMap::absorb(Object& into_object, Object& absorbed_object, const MergeLink& link) {
  Object* into = &into_object;
  Object* absorbed = &absorbed_object;
  into->voxels.write().merge(*absorbed->voxels);
  // `near` is the 3×3×3 dilation of the voxels (with each voxel's hits), so the joined object's
  // is the union of the two, the hits added: absorbed's entries are added as they are (its
  // neighbour-only entries with 0), rather than its new voxels dilated again (27 lookups each).
  auto& into_near = into->near.write();
  into_near.reserve(into_near.size() + absorbed->near->size());
  absorbed->near->for_each([&](VoxelKey key, std::uint8_t hits) {
    std::uint8_t& h = into_near[key];
    h = static_cast<std::uint8_t>(std::min(255, h + hits));
  });
  for (double t : absorbed->frames) into->add_frame(t);
  into->points.points.insert(into->points.points.end(), absorbed->points.points.begin(),
                             absorbed->points.points.end());
  into->points.colors.insert(into->points.colors.end(), absorbed->points.colors.begin(),
                             absorbed->points.colors.end());
  into->refresh();
  for (const auto& [name, vote] : absorbed->histogram) {
    into->histogram[name].score_sum += vote.score_sum;
    into->histogram[name].count += vote.count;
  }
  into->score_sum += absorbed->score_sum;
  into->observations += absorbed->observations;
  into->track_ids.insert(absorbed->track_ids.begin(), absorbed->track_ids.end());
  into->first_seen = std::min(into->first_seen, absorbed->first_seen);
  into->last_seen = std::max(into->last_seen, absorbed->last_seen);
  // Provenance by timestamp, then insertion order; the cells follow their entries.
  into->provenance.insert(into->provenance.end(), absorbed->provenance.begin(),
                          absorbed->provenance.end());
  for (auto& c : absorbed->cells) into->cells.push_back(std::move(c));
  into->sort_provenance();
  into->merges.push_back(link);
  into->merges.insert(into->merges.end(), absorbed->merges.begin(), absorbed->merges.end());
  absorbed->alive = false;
  absorbed->absorbed_into = into->id;
  absorbed->changed();
  absorbed->voxels = VoxelMap(VoxelMapOptions{options_.voxel_m, 1});  // free its memory
  absorbed->near = geometry::VoxelHashTable<std::uint8_t>();
  absorbed->frames.clear();
  absorbed->provenance.clear();
  absorbed->cells.clear();
  absorbed->merges.clear();
  absorbed->points = PointCloud();
}

const char* to_string(MergeRefusal refusal) {
  switch (refusal) {
    case MergeRefusal::kNone:
      return "none";
    case MergeRefusal::kClass:
      return "class";
    case MergeRefusal::kSharedFrames:
      return "shared_frames";
    case MergeRefusal::kScore:
      return "score";
    case MergeRefusal::kOverlap:
      return "overlap";
  }
  return "none";
}

MergeVerdict ObjectMap::judge_pair(const Object& a, const Object& b, bool full) const {
  MergeVerdict v;
  v.a = a.id;
  v.b = b.id;
  const auto refuse = [&](MergeRefusal r) {
    if (v.refused == MergeRefusal::kNone) v.refused = r;
  };
  if ((options_.require_same_class || options_.merge_require_same_class) &&
      segmentation::canonical_class(voted_class(a)) !=
          segmentation::canonical_class(voted_class(b))) {
    refuse(MergeRefusal::kClass);
    if (!full) return v;
  }
  // Shared keyframes: those where both objects took an observation labelled with their (common)
  // voted class. Two books stacked are both "book" in the same frames; a keyboard that the
  // detector also boxed as "laptop" in some frames is one object seen twice, not two objects.
  const std::string cls = segmentation::canonical_class(voted_class(a));
  const std::vector<double> fa = class_frames(a, cls), fb = class_frames(b, cls);
  std::size_t shared = 0;
  for (double t : fa) shared += std::binary_search(fb.begin(), fb.end(), t);
  const std::size_t nfr = std::min(a.frames.size(), b.frames.size());
  v.shared_frames = static_cast<int>(shared);
  v.smaller_frames = static_cast<int>(nfr);
  if (static_cast<double>(shared) > options_.merge_max_shared_frames * static_cast<double>(nfr)) {
    refuse(MergeRefusal::kSharedFrames);
    if (!full) return v;
  }
  bool same_id = false;
  for (int t : a.track_ids) same_id = same_id || b.track_ids.count(t) > 0;
  // M: the smaller object against the larger (containment: the share of the smaller on the
  // larger). The pass lets score() skip M when P cannot pass the threshold anyway; the verdict
  // computes it (the refusal is the same: P <= K either way).
  const bool a_small = a.voxels->size() <= b.voxels->size();
  const Object& small = a_small ? a : b;
  const Object& large = a_small ? b : a;
  const double threshold =
      full ? -std::numeric_limits<double>::infinity() : options_.merge_threshold;
  const Scores s = score(same_id, small.centroid, small.radius, *small.voxels, small.lo, small.hi,
                         large, threshold);
  v.p_id = s.p_id;
  v.distance_m = s.distance_m;
  v.overlap = s.overlap;
  v.score_p = s.score_p;
  if (!(s.score_p > options_.merge_threshold)) refuse(MergeRefusal::kScore);
  if (!(s.overlap >= options_.merge_min_overlap)) refuse(MergeRefusal::kOverlap);
  return v;
}

MergeVerdict ObjectMap::merge_verdict(int a, int b) const {
  const auto live = [&](int id) {
    require(id >= 0 && id < static_cast<int>(objects_.size()) && objects_[id]->alive,
            "ObjectMap::merge_verdict", "object " + std::to_string(id) + " is not a live object");
    return objects_[id].get();
  };
  const Object* x = live(a);
  const Object* y = live(b);
  require(a != b, "ObjectMap::merge_verdict", "an object with itself (" + std::to_string(a) + ")");
  // The pass scores each pair as (lower id, higher id).
  return a < b ? judge_pair(*x, *y, /*full=*/true) : judge_pair(*y, *x, /*full=*/true);
}

std::vector<MergeLink> ObjectMap::merge_pass() {
  std::vector<MergeLink> made;
  if (pair_cache_) pair_cache_->begin_pass();
  // The pair rule, then the rules for class confusions and fragments, until none joins anything:
  // an object that absorbed a fragment is larger, and a pair that the score refused before may now
  // pass (one chair seen from its two sides, its views apart joined by a fragment's).
  while (true) {
    const std::size_t before = made.size();
    merge_scored_pairs(made);
    if (options_.merge_class_confusions) merge_class_confusions(made);
    if (options_.merge_fragments_in_box) merge_fragments_in_box(made);
    if (made.size() == before) return made;
  }
}

void ObjectMap::merge_scored_pairs(std::vector<MergeLink>& made) {
  // Scores of every live pair (i < j), computed once; after a merge only the pairs of the grown
  // object are computed again (those of the absorbed one are dropped).
  struct Pair {
    int i, j;
    Scores s;
  };
  // Each object's content hash (pair_cache_), made when first needed and again when it grew.
  std::vector<std::optional<std::uint64_t>> content(objects_.size());
  const auto content_of = [&](const Object& o) {
    std::optional<std::uint64_t>& c = content[static_cast<std::size_t>(o.id)];
    if (!c) c = pair_content(o);
    return *c;
  };
  auto pair_score = [&](const Object& a, const Object& b, Scores& s) {
    std::uint64_t ca = 0, cb = 0;
    if (pair_cache_) {
      ca = content_of(a);
      cb = content_of(b);
      if (const std::optional<PairCache::Verdict> v = pair_cache_->find(ca, cb)) {
        s = Scores{v->p_id, v->distance_m, v->overlap, v->score_p};
        return v->passes;
      }
    }
    const MergeVerdict v = judge_pair(a, b, /*full=*/false);
    s = Scores{v.p_id, v.distance_m, v.overlap, v.score_p};
    const bool passes = v.refused == MergeRefusal::kNone;
    if (pair_cache_) pair_cache_->put(ca, cb, {v.p_id, v.distance_m, v.overlap, v.score_p, passes});
    return passes;
  };
  std::vector<Pair> pairs;  // only pairs above the threshold, in (i, j) order
  for (std::size_t i = 0; i < objects_.size() && options_.final_merge; ++i) {
    if (!objects_[i]->alive) continue;
    for (std::size_t j = i + 1; j < objects_.size(); ++j) {
      if (!objects_[j]->alive) continue;
      Scores s;
      if (pair_score(*objects_[i], *objects_[j], s))
        pairs.push_back({static_cast<int>(i), static_cast<int>(j), s});
    }
  }
  while (true) {
    // The highest P; ties: the first pair in (i, j) order.
    const Pair* best_pair = nullptr;
    for (const Pair& p : pairs)
      if (!best_pair || p.s.score_p > best_pair->s.score_p ||
          (p.s.score_p == best_pair->s.score_p &&
           std::make_pair(p.i, p.j) < std::make_pair(best_pair->i, best_pair->j)))
        best_pair = &p;
    if (!best_pair) break;
    Object* into = objects_[best_pair->i].get();
    Object* absorbed = objects_[best_pair->j].get();
    const Scores best = best_pair->s;

    // Join `absorbed` into `into` (the lower id).
    MergeLink link{into->id, absorbed->id, best.p_id, best.distance_m, best.overlap, best.score_p};
    absorb(*into, *absorbed, link);
    made.push_back(link);
    content[static_cast<std::size_t>(into->id)].reset();

    // The pairs of `into` change, those of `absorbed` are gone.
    const int a = into->id, b = absorbed->id;
    pairs.erase(
        std::remove_if(pairs.begin(), pairs.end(),
                       [&](const Pair& p) { return p.i == a || p.j == a || p.i == b || p.j == b; }),
        pairs.end());
    for (const auto& other : objects_) {
      if (!other->alive || other->id == a) continue;
      const Object& lo = other->id < a ? *other : *into;
      const Object& hi = other->id < a ? *into : *other;
      Scores s;
      if (pair_score(lo, hi, s)) pairs.push_back({lo.id, hi.id, s});
    }
    std::sort(pairs.begin(), pairs.end(), [](const Pair& x, const Pair& y) {
      return std::make_pair(x.i, x.j) < std::make_pair(y.i, y.j);
    });
  }
}

double ObjectMap::supported_share(const Object& a, const Object& b) const {
  // b's voxels that were in at least confusion_min_support of its observations: its surface, not
  // what its masks bled onto in a few views (a mouse beside a keyboard's box).
  const double need =
      std::min(255.0, std::max(1.0, options_.confusion_min_support * b.observations));
  const auto& offsets = geometry::neighbourhood_offsets();
  const int reach = options_.overlap_tolerance_voxels;
  std::size_t shared = 0;
  a.voxels->for_each([&](VoxelKey key, const VoxelData&) {
    if (reach == 0) {
      const std::uint8_t* hits = b.near->find(key);
      shared += hits && *hits >= need;
      return;
    }
    for (VoxelKey off : offsets) {
      const std::uint8_t* hits = b.near->find(key + off);
      if (hits && *hits >= need) {
        ++shared;
        return;
      }
    }
  });
  return static_cast<double>(shared) /
         static_cast<double>(std::max<std::size_t>(1, a.voxels->size()));
}

double ObjectMap::cached_supported_share(const Object& a, const Object& b) const {
  if (!pair_cache_) return supported_share(a, b);
  const std::uint64_t ca = pair_content(a), cb = pair_content(b);
  if (const std::optional<double> share = pair_cache_->shares.find(ca, cb)) return *share;
  const double share = supported_share(a, b);
  pair_cache_->shares.put(ca, cb, share);
  return share;
}

void ObjectMap::merge_class_confusions(std::vector<MergeLink>& made) {
  while (true) {
    // The pair (smaller, larger) with the highest containment of the smaller in the larger (ties:
    // the lower ids), among objects of different voted classes where the larger has enough views.
    Object* best_small = nullptr;
    Object* best_large = nullptr;
    Scores best;
    // Each live object's views and canonical class, once per round (not once per pair).
    std::vector<double> views(objects_.size(), 0.0);
    std::vector<std::string> classes(objects_.size());
    for (const auto& o : objects_)
      if (o->alive) {
        views[o->id] = count_views(o->provenance, options_);
        classes[o->id] = segmentation::canonical_class(voted_class(*o));
      }
    for (const auto& a : objects_) {
      if (!a->alive) continue;
      for (const auto& b : objects_) {
        if (!b->alive || a == b || a->voxels->size() > b->voxels->size()) continue;
        if (a->voxels->size() == b->voxels->size() && a->id > b->id) continue;
        if (views[b->id] < options_.confusion_min_view_ratio * views[a->id]) continue;
        if (classes[b->id] == classes[a->id]) continue;
        // The containment of a in b (whatever the configured measure of eq 21); P is no
        // criterion here.
        const int t = options_.overlap_tolerance_voxels;
        if (((a->hi.array() + t) < b->lo.array()).any() ||
            ((b->hi.array() + t) < a->lo.array()).any())
          continue;
        Scores s;
        s.distance_m = (a->centroid - b->centroid).norm();
        s.overlap = cached_supported_share(*a, *b);
        if (s.overlap < options_.confusion_min_containment) continue;
        if (!best_small || s.overlap > best.overlap) {
          best_small = a.get();
          best_large = b.get();
          best = s;
        }
      }
    }
    if (!best_small) return;
    MergeLink link{best_large->id, best_small->id, best.p_id, best.distance_m,
                   best.overlap,   best.score_p,   true};
    absorb(*best_large, *best_small, link);
    made.push_back(link);
  }
}

void ObjectMap::merge_fragments_in_box(std::vector<MergeLink>& made) {
  const double grow = options_.voxel_m;
  // Each live object's views, canonical class, surface and the oriented box of it; after a merge
  // only the grown object's entry is made again.
  struct Live {
    Object* object;
    int views;
    std::string cls;
    std::shared_ptr<const std::vector<Vec3>> surface;
    Obb box;
  };
  const auto make_live = [&](Object* o) {
    Live l{o, count_views(o->provenance, options_), segmentation::canonical_class(voted_class(*o)),
           surface_points(*o, 0.1), Obb{}};
    PointCloud cloud;
    for (const Vec3& p : *l.surface) cloud.points.push_back(p.cast<float>());
    l.box = geometry::compute_obb(cloud);
    return l;
  };
  std::vector<Live> live;
  for (const auto& o : objects_)
    if (o->alive) live.push_back(make_live(o.get()));
  while (true) {
    std::size_t best_small = 0, best_large = 0;
    double best_inside = -1.0;
    for (std::size_t ia = 0; ia < live.size(); ++ia)
      for (std::size_t ib = 0; ib < live.size(); ++ib) {
        const Live& a = live[ia];
        const Live& b = live[ib];
        if (ia == ib || a.cls != b.cls) continue;
        if (b.views < options_.fragment_min_view_ratio * a.views) continue;
        const int t = 1;
        if (((a.object->hi.array() + t) < b.object->lo.array()).any() ||
            ((b.object->hi.array() + t) < a.object->lo.array()).any())
          continue;
        std::vector<double> shared;
        std::set_intersection(a.object->frames.begin(), a.object->frames.end(),
                              b.object->frames.begin(), b.object->frames.end(),
                              std::back_inserter(shared));
        if (shared.size() > options_.merge_max_shared_frames * a.object->frames.size()) continue;
        std::size_t inside = 0;
        for (const Vec3& p : *a.surface) {
          const Vec3 local = b.box.rotation.transpose() * (p - b.box.center);
          inside += (local.array().abs() <= b.box.half_extent.array() + grow).all();
        }
        const double share = static_cast<double>(inside) /
                             static_cast<double>(std::max<std::size_t>(1, a.surface->size()));
        if (share < options_.fragment_min_inside || share <= best_inside) continue;
        best_small = ia;
        best_large = ib;
        best_inside = share;
      }
    if (best_inside < 0.0) return;
    Object& large = *live[best_large].object;
    Object& small = *live[best_small].object;
    MergeLink link{large.id,    small.id, 0.0,   (small.centroid - large.centroid).norm(),
                   best_inside, 0.0,      false, true};
    absorb(large, small, link);
    made.push_back(link);
    live[best_large] = make_live(&large);
    live.erase(live.begin() + static_cast<std::ptrdiff_t>(best_small));
  }
}

}  // namespace objmap::fusion
