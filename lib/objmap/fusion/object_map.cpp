#include "objmap/fusion/object_map.h"

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

void ObjectMapOptions::check() const {
  auto finite_nonneg = [](double v) { return std::isfinite(v) && v >= 0.0; };
  require(std::isfinite(voxel_m) && voxel_m >= 1e-4 && voxel_m <= 100.0, "ObjectMapOptions.voxel_m",
          "must be in [0.0001, 100] metres, got " + std::to_string(voxel_m));
  require(std::isfinite(distance_gate_m) && distance_gate_m > 0.0,
          "ObjectMapOptions.distance_gate_m",
          "must be > 0, got " + std::to_string(distance_gate_m));
  require(std::isfinite(gate_radius_factor) && gate_radius_factor >= 0.0,
          "ObjectMapOptions.gate_radius_factor",
          "must be >= 0, got " + std::to_string(gate_radius_factor));
  require(
      overlap_measure == OverlapMeasure::kIou || overlap_measure == OverlapMeasure::kContainment,
      "ObjectMapOptions.overlap_measure", "must be kIou or kContainment");
  require(overlap_tolerance_voxels == 0 || overlap_tolerance_voxels == 1,
          "ObjectMapOptions.overlap_tolerance_voxels",
          "must be 0 or 1, got " + std::to_string(overlap_tolerance_voxels));
  require(std::isfinite(merge_min_overlap) && merge_min_overlap >= 0.0 && merge_min_overlap <= 1.0,
          "ObjectMapOptions.merge_min_overlap",
          "must be in [0, 1], got " + std::to_string(merge_min_overlap));
  require(std::isfinite(merge_max_shared_frames) && merge_max_shared_frames >= 0.0 &&
              merge_max_shared_frames <= 1.0,
          "ObjectMapOptions.merge_max_shared_frames",
          "must be in [0, 1], got " + std::to_string(merge_max_shared_frames));
  require(finite_nonneg(weight_id), "ObjectMapOptions.weight_id",
          "must be >= 0, got " + std::to_string(weight_id));
  require(finite_nonneg(weight_distance), "ObjectMapOptions.weight_distance",
          "must be >= 0, got " + std::to_string(weight_distance));
  require(finite_nonneg(weight_overlap), "ObjectMapOptions.weight_overlap",
          "must be >= 0, got " + std::to_string(weight_overlap));
  require(weight_id + weight_distance + weight_overlap > 0.0, "ObjectMapOptions.weight_*",
          "at least one weight must be > 0");
  // P of eq 22 is at most w_id + w_d + w_m: a threshold at or above it matches nothing.
  const double p_max = weight_id + weight_distance + weight_overlap;
  require(finite_nonneg(match_threshold) && match_threshold < p_max,
          "ObjectMapOptions.match_threshold",
          "must be in [0, w_id + w_d + w_m = " + std::to_string(p_max) + "), got " +
              std::to_string(match_threshold) + " (P of eq 22 is at most that sum)");
  require(finite_nonneg(merge_threshold) && merge_threshold < p_max,
          "ObjectMapOptions.merge_threshold",
          "must be in [0, w_id + w_d + w_m = " + std::to_string(p_max) + "), got " +
              std::to_string(merge_threshold) + " (P of eq 22 is at most that sum)");
  require(
      std::isfinite(fragment_min_inside) && fragment_min_inside > 0.0 && fragment_min_inside <= 1.0,
      "ObjectMapOptions.fragment_min_inside",
      "must be in (0, 1], got " + std::to_string(fragment_min_inside));
  require(std::isfinite(fragment_min_view_ratio) && fragment_min_view_ratio >= 1.0,
          "ObjectMapOptions.fragment_min_view_ratio",
          "must be >= 1, got " + std::to_string(fragment_min_view_ratio));
  require(std::isfinite(bleed_min_inside) && bleed_min_inside > 0.0 && bleed_min_inside <= 1.0,
          "ObjectMapOptions.bleed_min_inside",
          "must be in (0, 1], got " + std::to_string(bleed_min_inside));
  require(std::isfinite(span_min_share) && span_min_share > 0.0 && span_min_share <= 0.5,
          "ObjectMapOptions.span_min_share",
          "must be in (0, 0.5], got " + std::to_string(span_min_share));
  require(std::isfinite(bleed_min_ratio) && bleed_min_ratio >= 1.0,
          "ObjectMapOptions.bleed_min_ratio",
          "must be >= 1, got " + std::to_string(bleed_min_ratio));
  require(split_cell_voxels >= 1 && split_cell_voxels <= 64, "ObjectMapOptions.split_cell_voxels",
          "must be in [1, 64], got " + std::to_string(split_cell_voxels));
  for (const auto& [name, v] : {std::make_pair("split_min_share", split_min_share),
                                std::make_pair("split_cover_share", split_cover_share),
                                std::make_pair("split_max_joint", split_max_joint)})
    require(std::isfinite(v) && v > 0.0 && v <= 1.0, std::string("ObjectMapOptions.") + name,
            "must be in (0, 1], got " + std::to_string(v));
  require(min_observations >= 1, "ObjectMapOptions.min_observations",
          "must be >= 1, got " + std::to_string(min_observations));
  require(
      std::isfinite(min_detected_share) && min_detected_share >= 0.0 && min_detected_share <= 1.0,
      "ObjectMapOptions.min_detected_share",
      "must be in [0, 1], got " + std::to_string(min_detected_share));
  require(min_points >= 1, "ObjectMapOptions.min_points",
          "must be >= 1, got " + std::to_string(min_points));
  require(std::isfinite(confusion_min_containment) && confusion_min_containment > 0.0 &&
              confusion_min_containment <= 1.0,
          "ObjectMapOptions.confusion_min_containment",
          "must be in (0, 1], got " + std::to_string(confusion_min_containment));
  require(std::isfinite(confusion_min_view_ratio) && confusion_min_view_ratio >= 1.0,
          "ObjectMapOptions.confusion_min_view_ratio",
          "must be >= 1, got " + std::to_string(confusion_min_view_ratio));
  require(std::isfinite(confusion_min_support) && confusion_min_support >= 0.0 &&
              confusion_min_support <= 1.0,
          "ObjectMapOptions.confusion_min_support",
          "must be in [0, 1], got " + std::to_string(confusion_min_support));
  require(finite_nonneg(view_min_translation_m), "ObjectMapOptions.view_min_translation_m",
          "must be >= 0, got " + std::to_string(view_min_translation_m));
  require(finite_nonneg(view_min_rotation_deg) && view_min_rotation_deg <= 180.0,
          "ObjectMapOptions.view_min_rotation_deg",
          "must be in [0, 180], got " + std::to_string(view_min_rotation_deg));
}

void set_paper_rules(ObjectMapOptions& o) {
  o.distance_gate_m = 0.1;
  o.gate_radius_factor = 0.0;
  o.distance_score = DistanceScore::kGate;
  o.overlap_measure = OverlapMeasure::kIou;
  o.overlap_tolerance_voxels = 0;
  o.weight_id = o.weight_distance = o.weight_overlap = 0.5;
  o.match_threshold = 0.4;
  o.require_same_class = false;
  o.one_observation_per_frame = false;
  o.best_first = false;
  o.final_merge = false;
  o.merge_class_confusions = false;
  o.merge_fragments_in_box = false;
  o.drop_bleed = false;
  o.drop_spanning = false;
  o.split_clusters = false;
  o.oversize.enabled = false;
  o.confirmation = Confirmation::kIdKeyframes;
  o.min_observations = 3;
  o.min_detected_share = 0.0;
  o.keep_points = true;
}

int count_views(const std::vector<ObservationLink>& provenance, const ObjectMapOptions& options) {
  const double min_rotation_rad = options.view_min_rotation_deg * M_PI / 180.0;
  int views = 0;
  const Pose* last = nullptr;  // the pose of the last view
  for (const ObservationLink& link : provenance) {
    if (!link.world_from_cam) {
      ++views;
      continue;
    }
    if (last) {
      const Pose last_from_this = last->inverse() * *link.world_from_cam;
      const double moved_m = last_from_this.translation().norm();
      const double turned_rad = Eigen::AngleAxisd(last_from_this.rotation()).angle();
      if (moved_m < options.view_min_translation_m && turned_rad < min_rotation_rad) continue;
    }
    ++views;
    last = &*link.world_from_cam;
  }
  return views;
}

const char* to_string(OverlapMeasure measure) {
  return measure == OverlapMeasure::kIou ? "iou" : "containment";
}

OverlapMeasure parse_overlap_measure(const std::string& text, const std::string& where) {
  if (text == "iou") return OverlapMeasure::kIou;
  if (text == "containment") return OverlapMeasure::kContainment;
  throw InputError(where, "unknown overlap measure '" + text + "'; expected iou or containment");
}

const char* to_string(DistanceScore score) {
  return score == DistanceScore::kGate ? "gate" : "linear";
}

DistanceScore parse_distance_score(const std::string& text, const std::string& where) {
  if (text == "linear") return DistanceScore::kLinear;
  if (text == "gate") return DistanceScore::kGate;
  throw InputError(where, "unknown distance score '" + text + "'; expected linear or gate");
}

const char* to_string(Confirmation confirmation) {
  return confirmation == Confirmation::kIdKeyframes ? "id_keyframes" : "views";
}

Confirmation parse_confirmation(const std::string& text, const std::string& where) {
  if (text == "views") return Confirmation::kViews;
  if (text == "id_keyframes") return Confirmation::kIdKeyframes;
  throw InputError(where, "unknown confirmation '" + text + "'; expected views or id_keyframes");
}

int count_id_keyframes(const std::vector<ObservationLink>& provenance) {
  std::map<std::optional<int>, std::set<double>> keyframes;  // track id (none: nullopt) -> stamps
  for (const ObservationLink& link : provenance) keyframes[link.track_id].insert(link.timestamp);
  std::size_t most = 0;
  for (const auto& entry : keyframes) most = std::max(most, entry.second.size());
  return static_cast<int>(most);
}

PointCloud voxel_nearest_centre(const PointCloud& cloud, double voxel_m,
                                const std::function<bool(VoxelKey)>& keep) {
  const float inv_voxel_m = static_cast<float>(1.0 / voxel_m);  // as VoxelMap::key_of
  struct Best {
    std::size_t index;
    float distance_sq;  // to the voxel's centre, in voxel units
  };
  std::map<VoxelKey, Best> best;  // sorted by key
  Eigen::Vector3i ijk;
  Eigen::Vector3f offset;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!geometry::voxel_coords(cloud.points[i], inv_voxel_m, ijk, offset)) continue;
    const VoxelKey key = geometry::pack_voxel(ijk.x(), ijk.y(), ijk.z());
    const float d = (offset - Eigen::Vector3f::Constant(0.5f)).squaredNorm();
    const auto [it, added] = best.try_emplace(key, Best{i, d});
    if (!added && d < it->second.distance_sq) it->second = Best{i, d};
  }
  PointCloud out;
  const bool colours = cloud.colors.size() == cloud.points.size();
  for (const auto& [key, b] : best) {
    if (keep && !keep(key)) continue;
    if (colours)
      out.push_back(cloud.points[b.index], cloud.colors[b.index]);
    else
      out.points.push_back(cloud.points[b.index]);
  }
  return out;
}

ObjectMap::ObjectMap(const ObjectMapOptions& options) : options_(options) { options_.check(); }
ObjectMap::~ObjectMap() = default;
ObjectMap::ObjectMap(ObjectMap&&) noexcept = default;
ObjectMap& ObjectMap::operator=(ObjectMap&&) noexcept = default;
ObjectMap::ObjectMap(const ObjectMap& other)
    : options_(other.options_),
      record_cache_(other.record_cache_),
      pair_cache_(other.pair_cache_),
      contact_cache_(other.contact_cache_),
      share_bar_(other.share_bar_) {
  objects_.reserve(other.objects_.size());
  for (const auto& o : other.objects_) objects_.push_back(std::make_unique<Object>(*o));
}
ObjectMap& ObjectMap::operator=(const ObjectMap& other) {
  if (this != &other) *this = ObjectMap(other);
  return *this;
}

std::string ObjectMap::voted_class(const Object& o) {
  // Score-weighted vote; ties: more observations, then the smaller name (deterministic). The
  // name split_oversize gave it for its size comes first.
  if (!o.size_class.empty()) return o.size_class;
  const std::pair<const std::string, ClassVote>* best = nullptr;
  for (const auto& entry : o.histogram) {
    if (!best || entry.second.score_sum > best->second.score_sum ||
        (entry.second.score_sum == best->second.score_sum &&
         entry.second.count > best->second.count))
      best = &entry;
  }
  return best ? best->first : std::string();
}

ObjectMap::Scores ObjectMap::score(bool same_id, const Vec3& centroid_a, double radius_a,
                                   const VoxelMap& a, const Eigen::Vector3i& a_lo,
                                   const Eigen::Vector3i& a_hi, const Object& b,
                                   double threshold) const {
  const ObjectMapOptions& o = options_;
  Scores s;
  s.p_id = same_id ? 1.0 : 0.0;
  // Eq 17: centroid distance, mapped to [0, 1] (1/2 at the size-scaled gate G).
  s.distance_m = (centroid_a - b.centroid).norm();
  const double gate =
      std::max(o.distance_gate_m, o.gate_radius_factor * std::max(radius_a, b.radius));
  const double f = o.distance_score == DistanceScore::kGate
                       ? (s.distance_m < gate ? 1.0 : 0.0)
                       : std::max(0.0, 1.0 - s.distance_m / (2.0 * gate));
  const double partial = o.weight_id * s.p_id + o.weight_distance * f;
  // Eq 21 only when it can change the decision: M <= 1 (IoU <= min(|A|,|B|)/max(|A|,|B|)), and 0
  // for voxel bounds further apart than the tolerance.
  const double na = static_cast<double>(a.size()), nb = static_cast<double>(b.voxels->size());
  const bool iou = o.overlap_measure == OverlapMeasure::kIou;
  const double bound = iou ? std::min(na, nb) / std::max(na, nb) : 1.0;
  const int t = o.overlap_tolerance_voxels;
  const bool disjoint =
      ((a_hi.array() + t) < b.lo.array()).any() || ((b.hi.array() + t) < a_lo.array()).any();
  if (!disjoint && na > 0 && partial + o.weight_overlap * bound > threshold) {
    const double common = static_cast<double>(shared_voxels(a, b));
    s.overlap = iou ? common / std::max(na, na + nb - common) : common / na;
  }
  // Eq 22.
  s.score_p = partial + o.weight_overlap * s.overlap;
  return s;
}

std::size_t ObjectMap::shared_voxels(const VoxelMap& a, const Object& b) const {
  if (options_.overlap_tolerance_voxels == 0) return fusion::common_voxels(a, *b.voxels);
  // Each key's slot in b.near is prefetched kAhead keys before it is looked up (a ring of the keys
  // seen), so that the cache misses of a large table overlap.
  constexpr std::size_t kAhead = 8;
  VoxelKey ring[kAhead];
  std::size_t n = 0, seen = 0;
  a.for_each([&](VoxelKey key, const VoxelData&) {
    VoxelKey& slot = ring[seen % kAhead];
    if (seen >= kAhead) n += b.near->contains(slot);
    b.near->prefetch(key);
    slot = key;
    ++seen;
  });
  for (std::size_t i = seen > kAhead ? seen - kAhead : 0; i < seen; ++i)
    n += b.near->contains(ring[i % kAhead]);
  return n;
}

struct ObjectMap::Prepared {
  VoxelMap voxels;
  Eigen::Vector3i lo, hi;
  Vec3 centroid = Vec3::Zero();
  explicit Prepared(double voxel_m) : voxels(VoxelMapOptions{voxel_m, 1}) {}
};

bool ObjectMap::prepare(const Observation& obs, Prepared& out) const {
  if (obs.points_in_world.size() < static_cast<std::size_t>(options_.min_points)) return false;
  out.voxels.insert(obs.points_in_world);
  if (!out.voxels.key_bounds(out.lo, out.hi)) return false;  // no finite point
  out.centroid = out.voxels.centroid();
  return true;
}

bool ObjectMap::candidate(const Observation& obs, const Prepared& prep, const Object& object,
                          double threshold, Scores& s) const {
  if (!object.alive) return false;
  if (options_.one_observation_per_frame && object.has_frame(obs.timestamp)) return false;
  if (options_.require_same_class && segmentation::canonical_class(voted_class(object)) !=
                                         segmentation::canonical_class(obs.class_name))
    return false;
  const bool same_id = obs.track_id && object.track_ids.count(*obs.track_id) > 0;
  // P <= w_id·P_ID + w_d + w_m: no need to score an object that cannot beat the threshold.
  const double ceiling = options_.weight_id * (same_id ? 1.0 : 0.0) + options_.weight_distance +
                         options_.weight_overlap;
  if (ceiling <= threshold) return false;
  s = score(same_id, prep.centroid, 0.0, prep.voxels, prep.lo, prep.hi, object, threshold);
  return s.score_p > threshold;
}

std::vector<AddResult> ObjectMap::add_frame_in_turn(const std::vector<Observation>& observations) {
  std::vector<AddResult> results(observations.size());
  for (std::size_t i = 0; i < observations.size(); ++i) {
    Prepared prep(options_.voxel_m);
    if (!prepare(observations[i], prep)) continue;
    // The highest P > K among the objects; ties: the lower id.
    Object* best = nullptr;
    Scores best_scores;
    for (auto& object : objects_) {
      Scores s;
      if (candidate(observations[i], prep, *object, options_.match_threshold, s) &&
          (!best || s.score_p > best_scores.score_p)) {
        best = object.get();
        best_scores = s;
      }
    }
    results[i] = fuse(observations[i], prep, best, best ? best_scores : Scores{});
  }
  return results;
}

bool ObjectMap::spans_two(const Observation& obs, const Prepared& prep) const {
  const std::string cls = segmentation::canonical_class(obs.class_name);
  const double need = options_.span_min_share * static_cast<double>(prep.voxels.size());
  std::vector<const Object*> on;  // the objects of its class it lies on
  for (const auto& op : objects_) {
    const Object& o = *op;
    if (!o.alive) continue;
    const int t = 1;
    if (((prep.hi.array() + t) < o.lo.array()).any() ||
        ((o.hi.array() + t) < prep.lo.array()).any())
      continue;
    if (segmentation::canonical_class(voted_class(o)) != cls) continue;
    if (count_views(o.provenance, options_) < options_.min_observations) continue;
    if (static_cast<double>(shared_voxels(prep.voxels, o)) < need) continue;
    // Two objects apart (a fragment of one object lies on it, and the merge pass joins them):
    // the smaller's voxels lie less than span_min_share on the larger; and seen as two in the
    // same keyframes (two halves of one object seen by turns are one object, and this mask says
    // so).
    for (const Object* other : on) {
      const Object& small = o.voxels->size() <= other->voxels->size() ? o : *other;
      const Object& large = &small == &o ? *other : o;
      std::vector<double> shared;
      std::set_intersection(small.frames.begin(), small.frames.end(), large.frames.begin(),
                            large.frames.end(), std::back_inserter(shared));
      if (shared.size() <= options_.merge_max_shared_frames * small.frames.size()) continue;
      if (static_cast<double>(shared_voxels(*small.voxels, large)) <
          options_.span_min_share * static_cast<double>(small.voxels->size()))
        return true;
    }
    on.push_back(&o);
  }
  return false;
}

std::vector<bool> ObjectMap::bleed(const std::vector<Observation>& observations,
                                   const std::vector<std::unique_ptr<Prepared>>& prep,
                                   const std::vector<bool>& open) const {
  const std::size_t n = observations.size();
  std::vector<bool> dropped(n, false);
  const auto& offsets = geometry::neighbourhood_offsets();
  for (std::size_t i = 0; i < n; ++i) {
    if (!open[i]) continue;
    const VoxelMap& a = prep[i]->voxels;
    const std::string cls = segmentation::canonical_class(observations[i].class_name);
    for (std::size_t j = 0; j < n && !dropped[i]; ++j) {
      if (j == i || !open[j]) continue;
      const VoxelMap& b = prep[j]->voxels;
      if (static_cast<double>(b.size()) < options_.bleed_min_ratio * static_cast<double>(a.size()))
        continue;
      if (segmentation::canonical_class(observations[j].class_name) != cls) continue;
      std::size_t on = 0;
      a.for_each([&](VoxelKey key, const VoxelData&) {
        for (VoxelKey off : offsets)
          if (b.contains(key + off)) {
            ++on;
            return;
          }
      });
      dropped[i] =
          static_cast<double>(on) >=
          options_.bleed_min_inside * static_cast<double>(std::max<std::size_t>(1, a.size()));
    }
  }
  return dropped;
}

std::vector<AddResult> ObjectMap::add_frame(const std::vector<Observation>& observations) {
  if (!options_.best_first) return add_frame_in_turn(observations);
  const std::size_t n = observations.size();
  std::vector<AddResult> results(n);
  std::vector<std::unique_ptr<Prepared>> prep(n);
  std::vector<bool> open(n, false);  // prepared and not fused yet
  for (std::size_t i = 0; i < n; ++i) {
    prep[i] = std::make_unique<Prepared>(options_.voxel_m);
    open[i] = prepare(observations[i], *prep[i]);
  }
  if (options_.drop_bleed) {
    const std::vector<bool> dropped = bleed(observations, prep, open);
    for (std::size_t i = 0; i < n; ++i)
      if (dropped[i]) {
        open[i] = false;
        results[i].bleed = true;
      }
  }
  if (options_.drop_spanning)
    for (std::size_t i = 0; i < n; ++i)
      if (open[i] && spans_two(observations[i], *prep[i])) {
        open[i] = false;
        results[i].spanning = true;
      }
  // Every candidate pair with P > K, scored once: a fused object takes no more observation of
  // this frame (one_observation_per_frame) or is scored again.
  struct Pair {
    std::size_t obs;
    int object;
    Scores s;
  };
  std::vector<Pair> pairs;
  const auto score_object = [&](std::size_t i, Object& object) {
    Scores s;
    if (candidate(observations[i], *prep[i], object, options_.match_threshold, s))
      pairs.push_back({i, object.id, s});
  };
  for (std::size_t i = 0; i < n; ++i)
    if (open[i])
      for (auto& object : objects_) score_object(i, *object);
  while (true) {
    const Pair* best = nullptr;
    for (const Pair& p : pairs) {
      if (!open[p.obs]) continue;
      if (!best || p.s.score_p > best->s.score_p ||
          (p.s.score_p == best->s.score_p &&
           std::make_pair(p.obs, p.object) < std::make_pair(best->obs, best->object)))
        best = &p;
    }
    if (!best) break;
    const Pair chosen = *best;
    Object& object = *objects_[static_cast<std::size_t>(chosen.object)];
    results[chosen.obs] = fuse(observations[chosen.obs], *prep[chosen.obs], &object, chosen.s);
    open[chosen.obs] = false;
    // The object changed: its pairs are scored again (none left with one observation per frame).
    pairs.erase(std::remove_if(pairs.begin(), pairs.end(),
                               [&](const Pair& p) { return p.object == chosen.object; }),
                pairs.end());
    for (std::size_t i = 0; i < n; ++i)
      if (open[i]) score_object(i, object);
  }
  for (std::size_t i = 0; i < n; ++i)
    if (open[i]) results[i] = fuse(observations[i], *prep[i], nullptr, Scores{});
  return results;
}

AddResult ObjectMap::fuse(const Observation& obs, const Prepared& prep, Object* best,
                          const Scores& best_scores) {
  AddResult result;
  const VoxelMap& obs_voxels = prep.voxels;
  const Vec3& obs_centroid = prep.centroid;
  if (!best) {
    objects_.push_back(std::make_unique<Object>(options_.voxel_m));
    best = objects_.back().get();
    best->id = static_cast<int>(objects_.size()) - 1;
    best->first_seen = best->last_seen = obs.timestamp;
    result.created = true;
  }

  // 4. Fuse: points into the voxel set, class vote, track ids, provenance.
  Object& o = *best;
  // Observation counts per voxel; a voxel with none so far is new to the object (its
  // neighbourhood joins `near`).
  std::vector<VoxelKey> new_keys;
  new_keys.reserve(obs_voxels.size());
  auto& near = o.near.write();
  near.reserve(near.size() + obs_voxels.size());
  const auto count_hit = [&](VoxelKey key) {
    std::uint8_t& hits = near[key];
    if (hits == 0) new_keys.push_back(key);
    if (hits < 255) ++hits;
  };
  // In the voxels' order, each slot prefetched kAhead voxels before (as in score()).
  constexpr std::size_t kAhead = 8;
  VoxelKey ring[kAhead];
  std::size_t seen = 0;
  obs_voxels.for_each([&](VoxelKey key, const VoxelData&) {
    VoxelKey& slot = ring[seen % kAhead];
    if (seen >= kAhead) count_hit(slot);
    near.prefetch(key);
    slot = key;
    ++seen;
  });
  for (std::size_t i = seen > kAhead ? seen - kAhead : 0; i < seen; ++i)
    count_hit(ring[i % kAhead]);
  o.voxels.write().merge(obs_voxels);
  o.dilate(new_keys);
  o.add_frame(obs.timestamp);
  if (options_.keep_points) {
    const PointCloud& p = obs.points_in_world;
    o.points.points.insert(o.points.points.end(), p.points.begin(), p.points.end());
    if (p.colors.size() == p.points.size())
      o.points.colors.insert(o.points.colors.end(), p.colors.begin(), p.colors.end());
    else
      o.points.colors.resize(o.points.points.size(), Rgb{});
  }
  o.refresh();
  ClassVote& vote = o.histogram[obs.class_name];
  vote.score_sum += obs.score;
  ++vote.count;
  o.score_sum += obs.score;
  ++o.observations;
  if (obs.track_id) o.track_ids.insert(*obs.track_id);
  o.first_seen = std::min(o.first_seen, obs.timestamp);
  o.last_seen = std::max(o.last_seen, obs.timestamp);

  ObservationLink link;
  link.timestamp = obs.timestamp;
  link.track_id = obs.track_id;
  link.class_name = obs.class_name;
  link.score = obs.score;
  link.keyframe_index = obs.keyframe_index;
  link.centroid_in_cam = obs.centroid_in_cam;
  link.world_from_cam = obs.world_from_cam;
  link.centroid_in_world = obs_centroid;
  link.points = obs.points_in_world.size();
  link.created = result.created;
  if (!result.created) {
    link.p_id = best_scores.p_id;
    link.distance_m = best_scores.distance_m;
    link.overlap = best_scores.overlap;
    link.score_p = best_scores.score_p;
  }
  o.provenance.push_back(link);
  if (options_.split_clusters || options_.oversize.enabled) {
    std::vector<VoxelKey> keys;
    keys.reserve(obs_voxels.size());
    obs_voxels.for_each([&](VoxelKey key, const VoxelData&) { keys.push_back(key); });
    o.cells.push_back(coarse_cells(std::move(keys), options_.split_cell_voxels));
  }

  result.object_id = o.id;
  result.p_id = link.p_id;
  result.distance_m = link.distance_m;
  result.overlap = link.overlap;
  result.score_p = link.score_p;
  return result;
}

std::size_t ObjectMap::size() const {
  std::size_t n = 0;
  for (const auto& o : objects_) n += o->alive;
  return n;
}

int ObjectMap::confirmation_count(const Object& object) const {
  return options_.confirmation == Confirmation::kIdKeyframes
             ? count_id_keyframes(object.provenance)
             : count_views(object.provenance, options_);
}

bool ObjectMap::confirmed(const Object& object) const {
  if (confirmation_count(object) < options_.min_observations) return false;
  if (share_bar_ <= 0.0 || object.frames_in_view <= 0) return true;
  const double share =
      static_cast<double>(object.frames.size()) / static_cast<double>(object.frames_in_view);
  return share >= share_bar_;
}

std::size_t ObjectMap::confirmed_count() const {
  std::size_t n = 0;
  for (const auto& o : objects_) n += o->alive && confirmed(*o);
  return n;
}

std::shared_ptr<const std::vector<Vec3>> ObjectMap::surface_points(const Object& o,
                                                                   double share) const {
  // Made once per content and share (the memo; its copies share it).
  ObjectMemo& memo = *o.memo;
  {
    const std::lock_guard<std::mutex> lock(memo.mutex);
    if (memo.surface && memo.surface_share == share) return memo.surface;
  }
  const double need = std::min(255.0, std::max(1.0, share * o.observations));
  auto seen = o.voxels->sorted_voxels([&](VoxelKey key) {
    const std::uint8_t* hits = o.near->find(key);
    return hits && *hits >= need;
  });
  if (seen.empty()) seen = o.voxels->sorted_voxels();
  auto surface = std::make_shared<std::vector<Vec3>>();
  surface->reserve(seen.size());
  for (const auto& [key, v] : seen) surface->push_back(o.voxels->mean_position(key, *v));
  const std::lock_guard<std::mutex> lock(memo.mutex);
  memo.surface_share = share;
  memo.surface = surface;
  return surface;
}

std::size_t ObjectMap::below_share_count() const {
  std::size_t n = 0;
  for (const auto& o : objects_)
    n += o->alive && confirmation_count(*o) >= options_.min_observations && !confirmed(*o);
  return n;
}

void ObjectMap::judge_visibility(const ViewLog& log, const VisibilityOptions& options,
                                 bool only_unjudged) {
  options.check();
  for (const auto& op : objects_) {
    Object& o = *op;
    if (!o.alive || (only_unjudged && o.frames_in_view >= 0)) continue;
    // The sample: evenly spaced among the voxels of its surface (seen in >= 10% of its
    // observations; all of them when none is), in key order.
    const std::shared_ptr<const std::vector<Vec3>> surface_memo = surface_points(o, 0.1);
    const std::vector<Vec3>& surface = *surface_memo;
    std::vector<Vec3> sample;
    const std::size_t n = std::min<std::size_t>(surface.size(), options.sample_points);
    for (std::size_t i = 0; i < n; ++i) sample.push_back(surface[i * surface.size() / n]);
    // The range: the farthest camera that detected it (no limit when one had no pose).
    double farthest = 0.0;
    bool every_pose = true;
    for (const ObservationLink& link : o.provenance) {
      if (!link.world_from_cam) every_pose = false;
      if (link.world_from_cam)
        farthest = std::max(farthest, (link.world_from_cam->translation() - o.centroid).norm());
    }
    const std::vector<double> in_view = log.frames_in_view(
        sample, o.centroid, every_pose ? farthest * options.range_factor : 0.0, options);
    std::vector<double> either;
    std::set_union(in_view.begin(), in_view.end(), o.frames.begin(), o.frames.end(),
                   std::back_inserter(either));
    o.frames_in_view = static_cast<int>(either.size());
  }
  // The bar: the higher of the floor and a share of the median among the objects with enough
  // views (the detector's recall on this recording).
  std::vector<double> shares;
  for (const auto& op : objects_)
    if (op->alive && op->frames_in_view > 0 && confirmation_count(*op) >= options_.min_observations)
      shares.push_back(static_cast<double>(op->frames.size()) / op->frames_in_view);
  share_bar_ = options_.min_detected_share;
  if (!shares.empty() && options_.min_detected_share > 0.0) {
    std::nth_element(shares.begin(), shares.begin() + shares.size() / 2, shares.end());
    share_bar_ =
        std::max(share_bar_, options_.detected_share_of_median * shares[shares.size() / 2]);
  }
}

int ObjectMap::resolve(int object_id) const {
  if (object_id < 0 || object_id >= static_cast<int>(objects_.size())) return -1;
  while (!objects_[object_id]->alive) object_id = objects_[object_id]->absorbed_into;
  return object_id;
}

int ObjectMap::resolve(int object_id, double timestamp) const {
  int id = resolve(object_id);
  // A part may have been cut again (split_oversize): follow the moves to the last part.
  for (std::size_t hops = 0; id >= 0 && hops < objects_.size(); ++hops) {
    const auto& moved = objects_[id]->moved;
    const auto it = std::lower_bound(moved.begin(), moved.end(),
                                     std::make_pair(timestamp, std::numeric_limits<int>::min()));
    if (it == moved.end() || it->first != timestamp) break;
    id = it->second;
  }
  return id;
}

Vec3 ObjectMap::centroid(int object_id) const {
  const int id = resolve(object_id);
  require(id >= 0, "ObjectMap::centroid", "unknown object id " + std::to_string(object_id));
  return objects_[id]->centroid;
}

}  // namespace objmap::fusion
