#pragma once
// ObjectMap's object, shared by the files that implement ObjectMap (object_map*.cpp: association,
// merges, splits, oversize cuts, records). Private to lib/objmap/fusion: include it from nowhere
// else.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "objmap/core/copy_on_write.h"
#include "objmap/fusion/object_map.h"
#include "objmap/geometry/bounds.h"
#include "objmap/geometry/voxel_key.h"

namespace objmap::fusion {

// Content hashes (ObjectMap::record_content, pair_content): splitmix64's finaliser, and a value's
// bits.
inline std::uint64_t content_mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

template <typename T>
std::uint64_t content_bits(T value) {
  static_assert(sizeof(T) <= sizeof(std::uint64_t));
  std::uint64_t b = 0;
  std::memcpy(&b, &value, sizeof(T));
  return b;
}

// An order-free hash of a table's entries (a sum and an xor of their hashes): a hash table's order
// depends on its history, not its content.
struct OrderFreeHash {
  std::uint64_t sum = 0, xr = 0;
  void add(std::uint64_t h) {
    sum += h;
    xr ^= content_mix(h);
  }
  std::uint64_t value(std::size_t entries) const {
    return content_mix(sum) ^ content_mix(xr ^ entries);
  }
};

// The hash of one voxel: its key and sums.
inline std::uint64_t voxel_content(VoxelKey key, const VoxelData& v) {
  std::uint64_t h = content_mix(key);
  for (int a = 0; a < 3; ++a)
    h = content_mix(h ^ content_bits(v.offset_sum[a]) ^ (content_bits(v.color_sum[a]) << 32));
  return content_mix(h ^ v.count ^ (std::uint64_t{v.color_count} << 32));
}

// What the finishing steps compute from one object's content again and again (its surface points,
// its pair content hash), kept until the object changes. An object copied (ObjectMap's copy: each
// publish of objmap follow) shares its memo with the copy until either changes: every change of
// the content gives the changed object a fresh memo (Object::changed), so a memo always belongs
// to one content. Several threads may fill and read one memo.
struct ObjectMemo {
  std::mutex mutex;
  double surface_share = -1.0;  // the share of `surface` (surface_points)
  std::shared_ptr<const std::vector<Vec3>> surface;
  std::optional<std::uint64_t> pair_content;
};

struct ObjectMap::Object {
  int id = -1;
  bool alive = true;
  int absorbed_into = -1;
  // The voxels and their neighbourhoods, shared with the object's copies until one changes them
  // (write()): a copy of the map (each publish of objmap follow) copies only what changes.
  CopyOnWrite<VoxelMap> voxels;
  Eigen::Vector3i lo = Eigen::Vector3i::Zero(), hi = Eigen::Vector3i::Zero();  // voxel bounds
  Vec3 centroid = Vec3::Zero();                                                // voxel-weighted
  double radius = 0.0;  // RMS distance of the voxels' mean positions from the centroid
  // Every voxel within one voxel (3×3×3) of an occupied voxel (the tolerant overlap test is one
  // lookup per voxel of the other set); the value is, for an occupied voxel, the number of
  // observations that had it (saturating at 255), 0 for a neighbour only.
  CopyOnWrite<geometry::VoxelHashTable<std::uint8_t>> near;
  std::vector<double> frames;  // timestamps of its observations, ascending, unique
  int frames_in_view = -1;     // judge_visibility(): keyframes in view or detected; -1: not judged
  bool has_frame(double t) const { return std::binary_search(frames.begin(), frames.end(), t); }
  void add_frame(double t) {
    auto it = std::lower_bound(frames.begin(), frames.end(), t);
    if (it == frames.end() || *it != t) frames.insert(it, t);
  }
  std::map<std::string, ClassVote> histogram;
  std::string size_class;  // split_oversize's name for its size (OversizeOptions::rename), or ""
  bool too_wide = false;   // split_oversize: one instance too wide for every class it was called
  double score_sum = 0.0;
  int observations = 0;
  std::set<int> track_ids;
  double first_seen = 0.0, last_seen = 0.0;
  std::vector<ObservationLink> provenance;
  // Per provenance entry, the coarse cells its voxels fell in (split_clusters; else empty).
  std::vector<std::vector<VoxelKey>> cells;
  std::vector<std::pair<double, int>> moved;  // split_pass(): observation timestamp -> its part
  std::vector<MergeLink> merges;
  PointCloud points;  // its observations' points (ObjectMapOptions::keep_points)
  std::shared_ptr<ObjectMemo> memo = std::make_shared<ObjectMemo>();

  explicit Object(double voxel_m) : voxels(VoxelMap(VoxelMapOptions{voxel_m, 1})) {}
  // Provenance by timestamp, then insertion order; the cells follow their entries (when every
  // entry has its cells; else none is kept).
  void sort_provenance() {
    const bool with_cells = cells.size() == provenance.size();
    std::vector<std::size_t> order(provenance.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) {
      return provenance[x].timestamp < provenance[y].timestamp;
    });
    std::vector<ObservationLink> sorted;
    std::vector<std::vector<VoxelKey>> sorted_cells;
    for (std::size_t i : order) {
      sorted.push_back(std::move(provenance[i]));
      if (with_cells) sorted_cells.push_back(std::move(cells[i]));
    }
    provenance = std::move(sorted);
    cells = std::move(sorted_cells);
  }
  // Takes one observation of another object's (a split's part): its provenance entry and coarse
  // cells, its class vote, track id and frame.
  void take(const ObservationLink& link, std::vector<VoxelKey> link_cells) {
    changed();
    ClassVote& vote = histogram[link.class_name];
    vote.score_sum += link.score;
    ++vote.count;
    score_sum += link.score;
    first_seen = observations == 0 ? link.timestamp : std::min(first_seen, link.timestamp);
    last_seen = observations == 0 ? link.timestamp : std::max(last_seen, link.timestamp);
    ++observations;
    if (link.track_id) track_ids.insert(*link.track_id);
    add_frame(link.timestamp);
    provenance.push_back(link);
    cells.push_back(std::move(link_cells));
  }
  // Marks the neighbourhoods of `keys` (voxels new to this object) in `near`.
  void dilate(const std::vector<VoxelKey>& keys) {
    const auto& offsets = geometry::neighbourhood_offsets();
    auto& near_voxels = near.write();
    near_voxels.reserve(near_voxels.size() + keys.size() * 4);
    // The 27 slots of a key two keys ahead are prefetched, so that the cache misses of a large
    // table overlap (the slots, not the values, depend on the order: the table ends the same).
    constexpr std::size_t kAhead = 2;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      if (i + kAhead < keys.size())
        for (VoxelKey off : offsets) near_voxels.prefetch(keys[i + kAhead] + off);
      for (VoxelKey off : offsets) near_voxels[keys[i] + off];  // inserted as 0 when absent
    }
  }
  // Whether the voxel bounds of this object and `other` are within `gap_m` of each other along
  // every world axis (one voxel of slack), at `voxel_m` a voxel.
  bool within(const Object& other, double gap_m, double voxel_m) const {
    const int reach = static_cast<int>(std::ceil(gap_m / voxel_m)) + 1;
    for (int k = 0; k < 3; ++k)
      if (lo[k] - other.hi[k] > reach || other.lo[k] - hi[k] > reach) return false;
    return true;
  }
  // The memo of the content before a change is not this object's any more: every step that
  // changes the content calls this (refresh() does; the counts, votes and links a step changes
  // beside the voxels are changed in the same step, before any memo is read).
  void changed() { memo = std::make_shared<ObjectMemo>(); }
  // Bounds, voxel-weighted centroid and RMS radius in one pass over the voxels.
  void refresh() {
    changed();
    Vec3 sum = Vec3::Zero();
    double sq = 0.0;
    bool any = false;
    voxels->for_each([&](VoxelKey key, const VoxelData& v) {
      geometry::extend_voxel_bounds(key, any, lo, hi);
      const Vec3 p = voxels->mean_position(key, v);
      sum += p;
      sq += p.squaredNorm();
    });
    const double n = static_cast<double>(voxels->size());
    centroid = n > 0 ? Vec3(sum / n) : Vec3::Zero();
    radius = n > 0 ? std::sqrt(std::max(0.0, sq / n - centroid.squaredNorm())) : 0.0;
  }
};

}  // namespace objmap::fusion
