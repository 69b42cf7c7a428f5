#pragma once
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "objmap/core/types.h"
#include "objmap/geometry/voxel_key.h"
#include "objmap/geometry/voxel_key_set.h"

// The dense map (paper §3.3): every back-projected point streamed into a voxel hash that keeps, per
// voxel, the running mean position, mean colour and point count.
// Memory grows with the mapped surface, not with the number of frames; frames are never
// concatenated.
namespace objmap::fusion {

using geometry::VoxelKey;
class FrameVoxels;

struct VoxelMapOptions {
  double voxel_m = 0.01;  // voxel edge; 1 cm as the paper's map
  int threads = 1;        // sorted_points() on this many threads; output identical for any count
  int shards = 0;  // hash tables the voxels are split into by key hash; 0 = `threads`. Maps with
                   // the same shard count can be merged shard by shard (merge_shard) in parallel
  void check() const;  // throws InputError naming the bad field
};

// What a voxel keeps. Positions are summed as offsets from the voxel's corner in voxel units
// (float, each in [0, 1), so the sum keeps its precision); colours and counts as integers.
struct VoxelData {
  float offset_sum[3] = {0.f, 0.f, 0.f};   // Σ (point − corner) / voxel_m
  std::uint32_t color_sum[3] = {0, 0, 0};  // Σ r, g, b over the points that had a colour
  std::uint32_t count = 0;                 // points that fell in the voxel
  std::uint32_t color_count = 0;           // of those, points with a colour

  Rgb mean_color() const;
};

class VoxelMap {
 public:
  explicit VoxelMap(const VoxelMapOptions& options = {});

  // Adds the points (world frame), on the calling thread; each voxel sees its points in input
  // order. Points that are not finite or out of the key range (±10 km at 1 cm) are dropped and
  // counted.
  void insert(const PointCloud& points_in_world);

  // Adds every voxel of `other` (same voxel size required): sums and counts. Used to join two
  // objects.
  void merge(const VoxelMap& other);

  // merge() restricted to shard `shard` of both maps (same voxel size and shard count required):
  // merges of different shards may run concurrently. Point counters are not touched (see
  // merge_counts). Each voxel of `other` is added once, so the result equals merge() of the same
  // maps in the same order.
  void merge_shard(const VoxelMap& other, std::size_t shard);
  // Adds a frame's voxel sums (frame_voxels.h, made for a map of this map's voxel size and shard
  // count) in their order: add_shard() one shard of them (no point counters; shards may be added
  // concurrently), add() all of them and the frame's point counters.
  void add_shard(const FrameVoxels& frame, std::size_t shard);
  void add(const FrameVoxels& frame);
  // Adds `other`'s points_inserted and points_dropped (the part of merge() merge_shard leaves out).
  void merge_counts(const VoxelMap& other);
  // The voxels for which `take(key)` is true, with their sums, in a map of this voxel size and
  // shard count; its points_inserted is the points of those voxels (an object split in parts).
  VoxelMap subset(const std::function<bool(VoxelKey)>& take) const;
  std::size_t shard_count() const { return shards_.size(); }
  // The shard of a voxel: by its x index (no second hash of the key): a frame spans many x slices,
  // so its voxels spread over the shards. A mask when the shard count is a power of two.
  std::size_t shard_of(VoxelKey key) const {
    const std::size_t x = static_cast<std::size_t>(key >> 42);
    return shard_mask_ != kNoMask ? x & shard_mask_ : x % shards_.size();
  }

  // Removes every voxel and zeroes the counters, keeping the tables' memory for reuse.
  void reset();

  // Pruning (fusion/dense_prune.h). From now on insert() and add_shard() remember the voxels they
  // open, so that prune_remembered() judges each of them once.
  // `rejudge`: a voxel that survives its judgement is judged again, 2, 4, 8, ... calls later, up to
  // this many more times (the cost stays amortised: each voxel is judged 1 + rejudge times at
  // most).
  void remember_new_voxels(int rejudge = 0);
  // Judges the voxels opened before the previous call (none at the first) and drops the noise;
  // keeps the voxels opened since for the next call. Returns how many were dropped. judge(keys,
  // voxels, noise) gets a shard's voxels at a time and sets noise[i] (0 or 1) for each; it is
  // called on `threads` threads at once and must only read. Every decision is taken before a voxel
  // is dropped, so the result depends neither on the order nor on the thread count. Nothing may be
  // added meanwhile.
  using Judge = std::function<void(const std::vector<VoxelKey>& keys,
                                   const std::vector<const VoxelData*>& voxels,
                                   std::vector<std::uint8_t>& noise)>;
  std::size_t prune_remembered(const Judge& judge);
  std::uint64_t voxels_pruned() const { return voxels_pruned_; }  // by prune_remembered, in all

  // Change tracking (a live map's cloud kept up to date, pipeline/dense_snapshot.h): from now on
  // every voxel insert(), add(), add_shard() or prune_remembered() adds to, opens or drops is
  // remembered (each key once, in shard order; not what merge(), reset() or take_sorted_points()
  // change); take_touched() hands them over and starts afresh.
  void track_touched();
  std::vector<VoxelKey> take_touched();
  // take_touched() one key at a time: f(key) for each, without a list of them all.
  template <typename F>
  void take_touched(F&& f) {
    for (geometry::VoxelKeySet& t : touched_) t.drain(f);
  }
  std::size_t touched_count() const;  // what take_touched() would give now

  // Room for this many voxels without rehashing (e.g. a per-frame map: ~1/4 of the pixels).
  void reserve(std::size_t voxels);

  double voxel_m() const { return voxel_m_; }
  std::size_t size() const;  // occupied voxels
  std::uint64_t points_inserted() const { return points_inserted_; }
  std::uint64_t points_dropped() const { return points_dropped_; }
  std::size_t memory_bytes() const;  // hash tables

  const VoxelData* find(VoxelKey key) const;
  void prefetch(VoxelKey key) const { shards_[shard_of(key)].prefetch(key); }  // a find() soon
  bool contains(VoxelKey key) const { return find(key) != nullptr; }
  VoxelKey key_of(const Vec3f& point_in_world) const {
    return geometry::voxel_key(point_in_world, inv_voxel_m_);
  }
  Vec3 mean_position(VoxelKey key, const VoxelData& voxel) const;
  // Voxel-space bounds of the occupied voxels (min/max of ix, iy, iz); false when empty.
  bool key_bounds(Eigen::Vector3i& lo, Eigen::Vector3i& hi) const;

  // f(key, data) for every occupied voxel, in hash order (for order-independent work: counting).
  template <typename F>
  void for_each(F&& f) const {
    for (const Table& t : shards_) t.for_each(f);
  }

  // Every occupied voxel as (key, data), sorted by key.
  // With `keep`: only the voxels it takes (filtered before they are sorted).
  std::vector<std::pair<VoxelKey, const VoxelData*>> sorted_voxels(
      const std::function<bool(VoxelKey)>& keep = {}) const;

  // One point per voxel at the voxel's mean position (mean_position, as float) with its mean
  // colour, sorted by voxel key: what to_cloud() holds, with the keys. Made in sequential passes
  // over the tables (no random access to the voxels) and sorted by x slice, on `threads` threads.
  // Left uninitialised by default (see DefaultInitAllocator): a long list is only touched, page by
  // page, as it is filled.
  struct VoxelPoint {
    VoxelKey key;
    Vec3f point;
    std::uint8_t r, g, b;
    Rgb color() const { return Rgb{r, g, b}; }
  };
  template <typename T>
  struct DefaultInitAllocator : std::allocator<T> {
    template <typename U>
    struct rebind {
      using other = DefaultInitAllocator<U>;
    };
    using std::allocator<T>::allocator;
    template <typename U>
    void construct(U* p) {
      ::new (static_cast<void*>(p)) U;
    }
    template <typename U, typename... Args>
    void construct(U* p, Args&&... args) {
      ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
  };
  using VoxelPoints = std::vector<VoxelPoint, DefaultInitAllocator<VoxelPoint>>;
  VoxelPoints sorted_points() const;
  // The point sorted_points() gives for a voxel.
  VoxelPoint voxel_point(VoxelKey key, const VoxelData& voxel) const {
    const Rgb c = voxel.mean_color();
    return VoxelPoint{key, mean_position(key, voxel).cast<float>(), c.r, c.g, c.b};
  }
  // sorted_points() that frees each table once read: the map is left empty, and its memory and the
  // list's are not both held at their full size.
  VoxelPoints take_sorted_points();

  // One point per voxel at the voxel's mean position with its mean colour, sorted by voxel key.
  PointCloud to_cloud() const;

  // Voxel-weighted centroid: the mean of the voxels' mean positions (0 when empty).
  Vec3 centroid() const;

 private:
  struct Run {  // consecutive points of one voxel, summed
    VoxelKey key = geometry::kNoVoxel;
    VoxelData sum;
  };
  static constexpr std::size_t kBatch = 1024;  // points per batch of runs (see insert_shard)
  using Table = geometry::VoxelHashTable<VoxelData>;
  static constexpr std::size_t kNoMask = ~std::size_t{0};
  VoxelPoints sorted_points_impl(bool release);  // release: free each shard once read
  // kAllShards: one pass that fills every shard (insert into a sharded map).
  static constexpr std::size_t kAllShards = ~std::size_t{0};
  std::size_t insert_shard(std::size_t shard, const PointCloud& cloud);
  // Adds a batch's m runs (in order) to shard `shard`'s table, or with kAllShards each to its own
  // (run_shard: scratch), prefetching ahead.
  void write_runs(const Run* runs, std::size_t m, std::size_t shard,
                  std::vector<std::uint32_t>& run_shard, std::vector<std::size_t>& per_shard);
  // Adds src to key's voxel; true when the voxel was opened by it.
  bool add_voxel(Table& table, VoxelKey key, const VoxelData& src);

  double voxel_m_;
  float inv_voxel_m_;
  std::size_t threads_ = 1;
  std::vector<Table> shards_;
  std::size_t shard_mask_ = kNoMask;  // shards_.size() - 1 when that is a power of two
  std::uint64_t points_inserted_ = 0;
  std::uint64_t points_dropped_ = 0;
  // Per shard, the voxels opened since the last prune_remembered() and before it
  // (remember_new_voxels; empty vectors: not remembered).
  std::vector<std::vector<VoxelKey>> young_, aging_;
  // Survivors to judge again: by (call number at which they are due, how many judgements they
  // passed), per shard.
  int rejudge_ = 0;
  std::size_t prunes_ = 0;  // calls of prune_remembered()
  std::map<std::pair<std::size_t, int>, std::vector<std::vector<VoxelKey>>> survivors_;
  std::uint64_t voxels_pruned_ = 0;
  // Per shard, the voxels touched since the last take_touched(), each once (track_touched; empty:
  // not tracked).
  std::vector<geometry::VoxelKeySet> touched_;
};

// Number of voxels present in both maps (same voxel size), |A ∩ B| of eq 21.
std::size_t common_voxels(const VoxelMap& a, const VoxelMap& b);

}  // namespace objmap::fusion
