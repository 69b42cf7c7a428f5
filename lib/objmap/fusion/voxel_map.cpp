#include "objmap/fusion/voxel_map.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <thread>

#include "objmap/core/error.h"
#include "objmap/core/parallel.h"
#include "objmap/fusion/frame_voxels.h"
#include "objmap/geometry/voxel_key_sse.h"

namespace objmap::fusion {

using geometry::kNoVoxel;

void VoxelMapOptions::check() const {
  require(std::isfinite(voxel_m) && voxel_m >= 1e-4 && voxel_m <= 100.0, "VoxelMapOptions.voxel_m",
          "must be in [0.0001, 100] metres, got " + std::to_string(voxel_m));
  require(threads >= 1 && threads <= 64, "VoxelMapOptions.threads",
          "must be in [1, 64], got " + std::to_string(threads));
  require(shards >= 0 && shards <= 4096, "VoxelMapOptions.shards",
          "must be in [0, 4096] (0 = threads), got " + std::to_string(shards));
}

Rgb VoxelData::mean_color() const {
  if (color_count == 0) return {128, 128, 128};
  auto avg = [&](std::uint32_t s) {
    return static_cast<std::uint8_t>((s + color_count / 2) / color_count);
  };
  return {avg(color_sum[0]), avg(color_sum[1]), avg(color_sum[2])};
}

namespace {

// Calls add(r) for r = 0 .. n-1 in order, the table slot of the voxel kAhead later prefetched
// (prefetch(r)) first, so that the cache misses of a large table overlap. The caller reserves
// room beforehand: no rehash may move the prefetched slots.
template <typename Prefetch, typename Add>
void add_in_order(std::size_t n, Prefetch&& prefetch, Add&& add) {
  constexpr std::size_t kAhead = 12;
  for (std::size_t r = 0; r < std::min(n, kAhead); ++r) prefetch(r);
  for (std::size_t r = 0; r < n; ++r) {
    if (r + kAhead < n) prefetch(r + kAhead);
    add(r);
  }
}

// A batch of points in voxel units, structure of arrays: voxel coordinates, offsets inside the
// voxel, valid (finite and in the key range).
struct BatchCells {
  std::int32_t *cx, *cy, *cz;
  float *fx, *fy, *fz;
  std::uint8_t* valid;
};

// Step 1 of an insert: the voxel coordinates and in-voxel offsets of `count` points: four points
// at a time with SSE2 (the same float operations as the scalar loop, so the same bits), the rest
// one by one.
inline void batch_cells(const Vec3f* points, std::size_t count, float inv_voxel,
                        const BatchCells& b) {
  constexpr float lim = static_cast<float>(geometry::kVoxelCoordLimit);
  std::int32_t *const cx = b.cx, *const cy = b.cy, *const cz = b.cz;
  float *const fx = b.fx, *const fy = b.fy, *const fz = b.fz;
  std::uint8_t* const valid = b.valid;
  std::size_t j = 0;
#if defined(__SSE2__)
  {
    const float* src = points->data();  // Vec3f: 3 packed floats per point
    const __m128 inv = _mm_set1_ps(inv_voxel);
    for (; j + 4 <= count; j += 4) {
      const __m128 a = _mm_loadu_ps(src + 3 * j);                        // x0 y0 z0 x1
      const __m128 b4 = _mm_loadu_ps(src + 3 * j + 4);                   // y1 z1 x2 y2
      const __m128 c = _mm_loadu_ps(src + 3 * j + 8);                    // z2 x3 y3 z3
      const __m128 bc = _mm_shuffle_ps(b4, c, _MM_SHUFFLE(1, 0, 3, 2));  // x2 y2 z2 x3
      const __m128 ab = _mm_shuffle_ps(a, b4, _MM_SHUFFLE(1, 0, 2, 1));  // y0 z0 y1 z1
      const __m128 cd = _mm_shuffle_ps(b4, c, _MM_SHUFFLE(2, 2, 3, 3));  // y2 y2 y3 y3
      const geometry::VoxelCoords4 v4 =
          geometry::voxel_coords4(_mm_mul_ps(_mm_shuffle_ps(a, bc, _MM_SHUFFLE(3, 0, 3, 0)), inv),
                                  _mm_mul_ps(_mm_shuffle_ps(ab, cd, _MM_SHUFFLE(2, 0, 2, 0)), inv),
                                  _mm_mul_ps(_mm_shuffle_ps(ab, c, _MM_SHUFFLE(3, 0, 3, 1)), inv));
      _mm_storeu_ps(fx + j, v4.fx);
      _mm_storeu_ps(fy + j, v4.fy);
      _mm_storeu_ps(fz + j, v4.fz);
      _mm_storeu_si128(reinterpret_cast<__m128i*>(cx + j), v4.ix);
      _mm_storeu_si128(reinterpret_cast<__m128i*>(cy + j), v4.iy);
      _mm_storeu_si128(reinterpret_cast<__m128i*>(cz + j), v4.iz);
      const int bits = _mm_movemask_ps(v4.ok);
      for (int k = 0; k < 4; ++k) valid[j + k] = static_cast<std::uint8_t>((bits >> k) & 1);
    }
  }
#endif
  for (; j < count; ++j) {
    const Vec3f& p = points[j];
    float sx = p.x() * inv_voxel, sy = p.y() * inv_voxel, sz = p.z() * inv_voxel;
    const bool ok = sx >= -lim && sx < lim && sy >= -lim && sy < lim && sz >= -lim && sz < lim;
    if (!ok) sx = sy = sz = 0.f;  // no float-to-int conversion of NaN or huge values
    const std::int32_t ix = geometry::fast_floor(sx), iy = geometry::fast_floor(sy),
                       iz = geometry::fast_floor(sz);
    cx[j] = ix;
    cy[j] = iy;
    cz[j] = iz;
    fx[j] = sx - static_cast<float>(ix);
    fy[j] = sy - static_cast<float>(iy);
    fz[j] = sz - static_cast<float>(iz);
    valid[j] = ok;
  }
}

// A batch's runs and the points of the batch dropped (not valid).
struct BatchRuns {
  std::size_t runs = 0;
  std::size_t dropped = 0;
};

// Step 2 of an insert: the batch's runs of consecutive points in one voxel, only those of the
// voxels that ours(key) keeps, into runs[0..]. The open run is summed in locals and appended when
// it ends (no store-to-load round trip through the run list per point); the additions are the
// same, in the same order. colors: the batch's colours, nullptr without.
template <typename Run, typename Ours>
inline BatchRuns batch_runs(const BatchCells& b, std::size_t count, const Rgb* colors,
                            const Ours& ours, Run* runs) {
  const bool colour = colors != nullptr;
  const std::int32_t *const cx = b.cx, *const cy = b.cy, *const cz = b.cz;
  const float *const fx = b.fx, *const fy = b.fy, *const fz = b.fz;
  const std::uint8_t* const valid = b.valid;
  BatchRuns out;
  std::size_t m = 0, dropped = 0;
  VoxelKey run_key = kNoVoxel;
  bool run_ours = false;
  float s0 = 0.f, s1 = 0.f, s2 = 0.f;
  std::uint32_t c0 = 0, c1 = 0, c2 = 0, points = 0;
  for (std::size_t i = 0; i <= count; ++i) {
    VoxelKey key = kNoVoxel;  // i == count: closes the last run
    if (i < count) {
      if (!valid[i]) {
        ++dropped;
        continue;
      }
      key = geometry::pack_voxel(cx[i], cy[i], cz[i]);
    }
    if (key != run_key) {
      if (run_ours) {
        Run& r = runs[m++];
        r.key = run_key;
        r.sum.offset_sum[0] = s0;
        r.sum.offset_sum[1] = s1;
        r.sum.offset_sum[2] = s2;
        r.sum.count = points;
        r.sum.color_sum[0] = c0;  // 0 without colours
        r.sum.color_sum[1] = c1;
        r.sum.color_sum[2] = c2;
        r.sum.color_count = colour ? points : 0;
      }
      if (i == count) break;
      run_key = key;
      run_ours = ours(key);
      s0 = s1 = s2 = 0.f;
      c0 = c1 = c2 = points = 0;
    }
    if (!run_ours) continue;
    s0 += fx[i];
    s1 += fy[i];
    s2 += fz[i];
    ++points;
    if (colour) {
      c0 += colors[i].r;
      c1 += colors[i].g;
      c2 += colors[i].b;
    }
  }
  out.runs = m;
  out.dropped = dropped;
  return out;
}

// work(t) on threads 0..threads-1 (0 on this thread), joined.
template <typename Work>
void on_threads(std::size_t threads, const Work& work) {
  std::vector<std::thread> pool;
  for (std::size_t t = 1; t < threads; ++t) pool.emplace_back([&, t] { work(t); });
  work(0);
  for (auto& th : pool) th.join();
}

using Tables = std::vector<geometry::VoxelHashTable<VoxelData>>;

// The x slices of a sorted list: the range of the keys' x, over every table.
struct XRange {
  std::uint64_t x0 = 0, x1 = 0;
};

// Step 1 of a sorted list: the x range, thread t reading tables t, t + threads, ...
XRange x_range(const Tables& shards, std::size_t threads) {
  std::vector<std::uint64_t> lo(threads, ~std::uint64_t{0}), hi(threads, 0);
  on_threads(threads, [&](std::size_t t) {
    for (std::size_t s = t; s < shards.size(); s += threads)
      shards[s].for_each([&](VoxelKey key, const VoxelData&) {
        lo[t] = std::min<std::uint64_t>(lo[t], key >> 42);
        hi[t] = std::max<std::uint64_t>(hi[t], key >> 42);
      });
  });
  return {*std::min_element(lo.begin(), lo.end()), *std::max_element(hi.begin(), hi.end())};
}

// Step 2 of a sorted list: the voxels per (thread, x slice), as offsets: at[t][i] is where thread
// t's part of slice i starts (after the earlier threads' parts); start[i] where slice i starts
// (start[slices]: the total).
void slice_offsets(const Tables& shards, std::size_t threads, std::uint64_t x0,
                   std::vector<std::vector<std::size_t>>& at, std::vector<std::size_t>& start) {
  const std::size_t slices = start.size() - 1;
  on_threads(threads, [&](std::size_t t) {
    for (std::size_t s = t; s < shards.size(); s += threads)
      shards[s].for_each([&](VoxelKey key, const VoxelData&) { ++at[t][(key >> 42) - x0]; });
  });
  for (std::size_t i = 0; i < slices; ++i) {
    std::size_t next = start[i];
    for (std::size_t t = 0; t < threads; ++t) {
      const std::size_t c = at[t][i];
      at[t][i] = next;
      next += c;
    }
    start[i + 1] = next;
  }
}

// Step 4 of a sorted list: the m points of one x slice sorted by key: bucketed by y (a counting
// sort into `scratch`), then each (x, y) row — a few dozen voxels — sorted by key (= by z). Keys
// are unique, so the order is the one a comparison sort of the whole list gives. `scratch` and
// `row` are kept from one slice to the next.
void sort_slice(VoxelMap::VoxelPoint* const first, std::size_t m,
                std::vector<VoxelMap::VoxelPoint>& scratch, std::vector<std::uint32_t>& row) {
  using VoxelPoint = VoxelMap::VoxelPoint;
  constexpr VoxelKey kAxis = (VoxelKey{1} << 21) - 1;
  const auto by_key = [](const VoxelPoint& a, const VoxelPoint& b) { return a.key < b.key; };
  if (m < 64) {
    std::sort(first, first + m, by_key);
    return;
  }
  VoxelKey y0 = kAxis, y1 = 0;
  for (std::size_t j = 0; j < m; ++j) {
    const VoxelKey y = (first[j].key >> 21) & kAxis;
    y0 = std::min(y0, y);
    y1 = std::max(y1, y);
  }
  // The buffers through local pointers: the stores below (VoxelPoint holds bytes) may then not
  // alias the vectors' own pointers, as they could through the references.
  row.assign(static_cast<std::size_t>(y1 - y0) + 2, 0);
  std::uint32_t* const rows = row.data();
  const std::size_t nrows = row.size();
  for (std::size_t j = 0; j < m; ++j) ++rows[((first[j].key >> 21) & kAxis) - y0 + 1];
  for (std::size_t r = 1; r < nrows; ++r) rows[r] += rows[r - 1];
  scratch.resize(m);
  VoxelPoint* const sorted = scratch.data();
  for (std::size_t j = 0; j < m; ++j)
    sorted[rows[((first[j].key >> 21) & kAxis) - y0]++] = first[j];
  // rows[r] is now the end of row r (the start of row r + 1).
  std::size_t begin = 0;
  for (std::size_t r = 0; r + 1 < nrows; ++r) {
    const std::size_t end = rows[r];
    if (end - begin > 32) {  // a long row (a wall along z)
      std::sort(sorted + begin, sorted + end, by_key);
      begin = end;
      continue;
    }
    for (std::size_t j = begin + 1; j < end; ++j) {  // insertion sort: rows are short
      const VoxelPoint v = sorted[j];
      std::size_t k = j;
      for (; k > begin && v.key < sorted[k - 1].key; --k) sorted[k] = sorted[k - 1];
      sorted[k] = v;
    }
    begin = end;
  }
  std::copy(sorted, sorted + m, first);
}

}  // namespace

VoxelMap::VoxelMap(const VoxelMapOptions& options) {
  options.check();
  voxel_m_ = options.voxel_m;
  inv_voxel_m_ = static_cast<float>(1.0 / options.voxel_m);
  threads_ = static_cast<std::size_t>(options.threads);
  shards_.resize(static_cast<std::size_t>(options.shards > 0 ? options.shards : options.threads));
  const std::size_t n = shards_.size();
  if ((n & (n - 1)) == 0) shard_mask_ = n - 1;
}

void VoxelMap::reset() {
  for (Table& t : shards_) t.reset();
  points_inserted_ = 0;
  points_dropped_ = 0;
  for (auto& keys : young_) keys.clear();
  for (auto& keys : aging_) keys.clear();
  survivors_.clear();
  prunes_ = 0;
  voxels_pruned_ = 0;
}

void VoxelMap::track_touched() { touched_.resize(shards_.size()); }

std::size_t VoxelMap::touched_count() const {
  std::size_t n = 0;
  for (const geometry::VoxelKeySet& t : touched_) n += t.size();
  return n;
}

std::vector<VoxelKey> VoxelMap::take_touched() {
  std::vector<VoxelKey> out;
  out.reserve(touched_count());
  for (geometry::VoxelKeySet& t : touched_) t.take(out);
  return out;
}

void VoxelMap::remember_new_voxels(int rejudge) {
  require(rejudge >= 0 && rejudge <= 16, "VoxelMap::remember_new_voxels",
          "rejudge must be in [0, 16], got " + std::to_string(rejudge));
  young_.resize(shards_.size());
  aging_.resize(shards_.size());
  rejudge_ = rejudge;
}

std::size_t VoxelMap::prune_remembered(const Judge& judge) {
  require(young_.size() == shards_.size(), "VoxelMap::prune_remembered",
          "the map does not remember its new voxels; call remember_new_voxels() first");
  const std::size_t n = shards_.size();
  const std::size_t now = prunes_++;
  // The survivors due now, and the lists the survivors of this call go to (made before the
  // threads start: each thread then writes only its own shard's vectors).
  std::vector<std::pair<int, std::vector<std::vector<VoxelKey>>>> due;
  for (auto it = survivors_.begin(); it != survivors_.end() && it->first.first == now;) {
    due.emplace_back(it->first.second, std::move(it->second));
    it = survivors_.erase(it);
  }
  std::vector<std::vector<std::vector<VoxelKey>>*> next(static_cast<std::size_t>(rejudge_));
  for (int round = 0; round < rejudge_; ++round) {
    auto& list = survivors_[{now + (std::size_t{2} << round), round + 1}];
    list.resize(n);
    next[static_cast<std::size_t>(round)] = &list;
  }
  // 1. The decisions, every shard's voxels on any thread (nothing changes yet): the voxels opened
  //    before the previous call (round 0), then the survivors due (round r: r judgements passed).
  std::vector<std::vector<VoxelKey>> drop(n);
  parallel_for(n, static_cast<int>(threads_), [&](std::size_t s) {
    std::vector<VoxelKey> keys = aging_[s];
    std::vector<int> rounds(keys.size(), 0);
    for (const auto& [round, lists] : due) {
      keys.insert(keys.end(), lists[s].begin(), lists[s].end());
      rounds.resize(keys.size(), round);
    }
    const Table& table = shards_[s];
    std::vector<const VoxelData*> voxels(keys.size());
    constexpr std::size_t kAhead = 8;  // the slots of later keys prefetched (cache misses overlap)
    for (std::size_t i = 0; i < keys.size(); ++i) {
      if (i + kAhead < keys.size()) table.prefetch(keys[i + kAhead]);
      voxels[i] = table.find(keys[i]);  // remembered voxels are dropped only here
    }
    std::vector<std::uint8_t> noise(keys.size(), 0);
    judge(keys, voxels, noise);
    for (std::size_t i = 0; i < keys.size(); ++i) {
      if (noise[i])
        drop[s].push_back(keys[i]);
      else if (rounds[i] < rejudge_)
        (*next[static_cast<std::size_t>(rounds[i])])[s].push_back(keys[i]);
    }
  });
  // 2. The drops, shard by shard; the voxels opened since the last call are judged by the next.
  std::size_t dropped = 0;
  for (std::size_t s = 0; s < n; ++s) dropped += drop[s].size();
  parallel_for(n, static_cast<int>(threads_), [&](std::size_t s) {
    for (VoxelKey key : drop[s]) shards_[s].erase(key);
    if (!touched_.empty())
      for (const VoxelKey key : drop[s]) touched_[s].insert(key);
    aging_[s].swap(young_[s]);
    young_[s].clear();
  });
  voxels_pruned_ += dropped;
  return dropped;
}

void VoxelMap::reserve(std::size_t voxels) {
  for (Table& t : shards_) t.reserve(voxels / shards_.size() + 1);
}

std::size_t VoxelMap::size() const {
  std::size_t n = 0;
  for (const Table& t : shards_) n += t.size();
  return n;
}

std::size_t VoxelMap::memory_bytes() const {
  std::size_t n = 0;
  for (const Table& t : shards_) n += t.memory_bytes();
  return n;
}

const VoxelData* VoxelMap::find(VoxelKey key) const { return shards_[shard_of(key)].find(key); }

Vec3 VoxelMap::mean_position(VoxelKey key, const VoxelData& v) const {
  const double c = v.count;
  return (geometry::unpack_voxel(key).cast<double>() +
          Vec3(v.offset_sum[0] / c, v.offset_sum[1] / c, v.offset_sum[2] / c)) *
         voxel_m_;
}

// Points of `cloud` whose voxel belongs to `shard`, in input order. Consecutive points of one voxel
// (neighbouring pixels) are summed locally into a run; the runs of a batch of points are then
// written to the table with the slot of a later run prefetched, so that the table's cache misses
// overlap (a random slot of a multi-megabyte table is the cost of the whole insert otherwise). The
// batch size is fixed, so the sums (and the map) do not depend on anything but the input. Returns
// the number of points dropped (not finite or out of range).
std::size_t VoxelMap::insert_shard(std::size_t shard, const PointCloud& cloud) {
  const bool colour = cloud.has_colors();
  const bool sharded = shard != kAllShards && shards_.size() > 1;
  const auto ours = [&](VoxelKey key) { return !sharded || shard_of(key) == shard; };
  std::vector<std::size_t> per_shard;
  std::vector<std::uint32_t> run_shard;
  const std::size_t n = cloud.size();
  std::size_t dropped = 0;
  std::vector<Run> runs(
      kBatch);  // at most one run per point; filled by index (no call in the loop)
  // Per point of a batch (structure of arrays): voxel coordinates, offsets inside the voxel, valid.
  std::vector<std::int32_t> cell(3 * kBatch);
  std::vector<float> frac(3 * kBatch);
  std::vector<std::uint8_t> valid(kBatch);
  const BatchCells cells{cell.data(), cell.data() + kBatch, cell.data() + 2 * kBatch,
                         frac.data(), frac.data() + kBatch, frac.data() + 2 * kBatch,
                         valid.data()};
  for (std::size_t begin = 0; begin < n; begin += kBatch) {
    const std::size_t count = std::min(n, begin + kBatch) - begin;
    // 1. Voxel coordinates and in-voxel offsets of the batch (SSE2, the same bits as scalar).
    batch_cells(cloud.points.data() + begin, count, inv_voxel_m_, cells);
    // 2. The batch's runs of consecutive points in one voxel (only this shard's voxels).
    const Rgb* colors = colour ? cloud.colors.data() + begin : nullptr;
    const BatchRuns batch = batch_runs(cells, count, colors, ours, runs.data());
    dropped += batch.dropped;
    // 3. The runs into the table(s), in order, prefetching ahead.
    write_runs(runs.data(), batch.runs, shard, run_shard, per_shard);
  }
  return dropped;
}

// No rehash below: prefetched slots stay valid.
void VoxelMap::write_runs(const Run* runs, std::size_t m, std::size_t shard,
                          std::vector<std::uint32_t>& run_shard,
                          std::vector<std::size_t>& per_shard) {
  const bool all = shard == kAllShards;
  if (all) {
    run_shard.resize(m);
    per_shard.assign(shards_.size(), 0);
    for (std::size_t r = 0; r < m; ++r) {
      run_shard[r] = static_cast<std::uint32_t>(shard_of(runs[r].key));
      ++per_shard[run_shard[r]];
    }
    for (std::size_t t = 0; t < shards_.size(); ++t)
      if (per_shard[t]) shards_[t].reserve(shards_[t].size() + per_shard[t]);
  } else {
    shards_[shard].reserve(shards_[shard].size() + m);
  }
  auto shard_of_run = [&](std::size_t r) { return all ? run_shard[r] : shard; };
  const bool remember = !young_.empty();  // the voxels opened, for prune_remembered()
  add_in_order(
      m, [&](std::size_t r) { shards_[shard_of_run(r)].prefetch(runs[r].key); },
      [&](std::size_t r) {
        const std::size_t s = shard_of_run(r);
        if (add_voxel(shards_[s], runs[r].key, runs[r].sum) && remember)
          young_[s].push_back(runs[r].key);
      });
}

void VoxelMap::insert(const PointCloud& cloud) {
  const std::size_t n = cloud.size();
  if (n == 0) return;
  // One pass; a sharded map gets each run routed to its shard.
  const std::size_t dropped = insert_shard(shards_.size() == 1 ? 0 : kAllShards, cloud);
  if (!touched_.empty())  // the points' voxels, out of the hot loop (tracking is rare)
    for (const Vec3f& p : cloud.points)
      if (const VoxelKey key = key_of(p); key != geometry::kNoVoxel)
        touched_[shard_of(key)].insert(key);
  points_inserted_ += n - dropped;
  points_dropped_ += dropped;
}

inline bool VoxelMap::add_voxel(Table& table, VoxelKey key, const VoxelData& src) {
  VoxelData& v = table[key];
  const bool opened = v.count == 0;  // an entry has points once added
  for (int a = 0; a < 3; ++a) {
    v.offset_sum[a] += src.offset_sum[a];
    v.color_sum[a] += src.color_sum[a];
  }
  v.count += src.count;
  v.color_count += src.color_count;
  return opened;
}

void VoxelMap::merge(const VoxelMap& other) {
  require(other.voxel_m_ == voxel_m_, "VoxelMap::merge",
          "voxel sizes differ (" + std::to_string(other.voxel_m_) + " vs " +
              std::to_string(voxel_m_) + "); expected equal");
  if (other.shards_.size() == shards_.size()) {
    for (std::size_t s = 0; s < shards_.size(); ++s) merge_shard(other, s);
    merge_counts(other);
    return;
  }
  // Each voxel of `other` is added once, so the visiting order changes no voxel's value (only the
  // hash layout, which no export depends on).
  other.for_each(
      [&](VoxelKey key, const VoxelData& v) { add_voxel(shards_[shard_of(key)], key, v); });
  merge_counts(other);
}

VoxelMap VoxelMap::subset(const std::function<bool(VoxelKey)>& take) const {
  VoxelMap out(
      VoxelMapOptions{voxel_m_, static_cast<int>(threads_), static_cast<int>(shards_.size())});
  for (const auto& [key, v] : sorted_voxels())
    if (take(key)) {
      out.add_voxel(out.shards_[out.shard_of(key)], key, *v);
      out.points_inserted_ += v->count;
    }
  return out;
}

void VoxelMap::merge_shard(const VoxelMap& other, std::size_t shard) {
  require(other.voxel_m_ == voxel_m_ && other.shards_.size() == shards_.size() &&
              shard < shards_.size(),
          "VoxelMap::merge_shard",
          "maps differ in voxel size or shard count, or no shard " + std::to_string(shard) +
              "; expected equal maps and a shard below " + std::to_string(shards_.size()));
  const Table& src = other.shards_[shard];
  Table& dst = shards_[shard];
  std::vector<std::pair<VoxelKey, const VoxelData*>> todo;
  todo.reserve(src.size());
  src.for_each([&](VoxelKey key, const VoxelData& v) { todo.emplace_back(key, &v); });
  dst.reserve(dst.size() + todo.size());
  add_in_order(
      todo.size(), [&](std::size_t r) { dst.prefetch(todo[r].first); },
      [&](std::size_t r) { add_voxel(dst, todo[r].first, *todo[r].second); });
}

void VoxelMap::add_shard(const FrameVoxels& frame, std::size_t shard) {
  require(frame.shard_count() == shards_.size() && frame.voxel_m() == voxel_m_ &&
              shard < shards_.size(),
          "VoxelMap::add_shard",
          "the frame's voxels were made for " + std::to_string(frame.shard_count()) +
              " shards of " + std::to_string(frame.voxel_m()) + " m voxels, or no shard " +
              std::to_string(shard) + "; expected this map's " + std::to_string(shards_.size()) +
              " shards of " + std::to_string(voxel_m_) + " m and a shard below that");
  const FrameVoxels::Entry* const first = frame.shard_begin(shard);
  const std::size_t n = static_cast<std::size_t>(frame.shard_end(shard) - first);
  Table& dst = shards_[shard];
  dst.reserve(dst.size() + n);
  if (!touched_.empty())
    add_in_order(
        n, [&](std::size_t r) { touched_[shard].prefetch(first[r].key); },
        [&](std::size_t r) { touched_[shard].insert(first[r].key); });
  if (young_.empty()) {
    add_in_order(
        n, [&](std::size_t r) { dst.prefetch(first[r].key); },
        [&](std::size_t r) { add_voxel(dst, first[r].key, first[r].sum); });
    return;
  }
  // The voxels this frame opens are remembered for prune_remembered().
  std::vector<VoxelKey>& young = young_[shard];
  add_in_order(
      n, [&](std::size_t r) { dst.prefetch(first[r].key); },
      [&](std::size_t r) {
        if (add_voxel(dst, first[r].key, first[r].sum)) young.push_back(first[r].key);
      });
}

void VoxelMap::add(const FrameVoxels& frame) {
  for (std::size_t s = 0; s < shards_.size(); ++s) add_shard(frame, s);
  points_inserted_ += frame.points() - frame.dropped();
  points_dropped_ += frame.dropped();
}

void VoxelMap::merge_counts(const VoxelMap& other) {
  points_inserted_ += other.points_inserted_;
  points_dropped_ += other.points_dropped_;
}

bool VoxelMap::key_bounds(Eigen::Vector3i& lo, Eigen::Vector3i& hi) const {
  bool any = false;
  for (const Table& t : shards_) {
    t.for_each(
        [&](VoxelKey key, const VoxelData&) { geometry::extend_voxel_bounds(key, any, lo, hi); });
  }
  return any;
}

std::vector<std::pair<VoxelKey, const VoxelData*>> VoxelMap::sorted_voxels(
    const std::function<bool(VoxelKey)>& keep) const {
  using Entry = std::pair<VoxelKey, const VoxelData*>;
  const auto by_key = [](const Entry& a, const Entry& b) { return a.first < b.first; };
  std::vector<Entry> out;
  out.reserve(size());
  if (shards_.size() == 1 || keep) {
    for (const Table& t : shards_)
      t.for_each([&](VoxelKey key, const VoxelData& v) {
        if (!keep || keep(key)) out.emplace_back(key, &v);
      });
    std::sort(out.begin(), out.end(), by_key);
    return out;
  }
  // Bucketed by x slice (counting sort on the x key), then each slice sorted on its own, `threads`
  // at a time: no second copy of the list.
  std::uint64_t lo = ~std::uint64_t{0}, hi = 0;
  for (const Table& t : shards_)
    t.for_each([&](VoxelKey key, const VoxelData&) {
      lo = std::min<std::uint64_t>(lo, key >> 42);
      hi = std::max<std::uint64_t>(hi, key >> 42);
    });
  const std::size_t n = size();
  if (n == 0) return out;
  std::vector<std::size_t> start(hi - lo + 2, 0);
  for (const Table& t : shards_)
    t.for_each([&](VoxelKey key, const VoxelData&) { ++start[(key >> 42) - lo + 1]; });
  for (std::size_t i = 1; i < start.size(); ++i) start[i] += start[i - 1];
  out.resize(n);
  std::vector<std::size_t> at(start.begin(), start.end() - 1);
  for (const Table& t : shards_)
    t.for_each([&](VoxelKey key, const VoxelData& v) { out[at[(key >> 42) - lo]++] = {key, &v}; });
  const std::size_t slices = start.size() - 1;
  auto sort_slices = [&](std::size_t t, std::size_t step) {
    for (std::size_t i = t; i < slices; i += step)
      std::sort(out.begin() + static_cast<std::ptrdiff_t>(start[i]),
                out.begin() + static_cast<std::ptrdiff_t>(start[i + 1]), by_key);
  };
  const std::size_t threads = std::min(threads_, slices);
  std::vector<std::thread> pool;
  for (std::size_t t = 1; t < threads; ++t) pool.emplace_back(sort_slices, t, threads);
  sort_slices(0, threads);
  for (auto& th : pool) th.join();
  return out;
}

VoxelMap::VoxelPoints VoxelMap::sorted_points() const {
  // sorted_points_impl(false) does not modify the map.
  return const_cast<VoxelMap*>(this)->sorted_points_impl(false);
}

VoxelMap::VoxelPoints VoxelMap::take_sorted_points() {
  VoxelPoints out = sorted_points_impl(true);
  points_inserted_ = points_dropped_ = 0;
  return out;
}

VoxelMap::VoxelPoints VoxelMap::sorted_points_impl(bool release) {
  VoxelPoints out;
  const std::size_t n = size();
  if (n == 0) return out;
  // Thread t takes shards t, t + threads, ... and slices t, t + threads, ...
  const std::size_t threads = std::max<std::size_t>(1, std::min(threads_, shards_.size()));
  // 1. The x range.
  const XRange x = x_range(shards_, threads);
  const std::size_t slices = static_cast<std::size_t>(x.x1 - x.x0 + 1);
  // 2. Voxels per (thread, x slice); each thread's part of each slice starts after the earlier
  //    threads' parts.
  std::vector<std::vector<std::size_t>> at(threads, std::vector<std::size_t>(slices, 0));
  std::vector<std::size_t> start(slices + 1, 0);
  slice_offsets(shards_, threads, x.x0, at, start);
  // 3. Each voxel's point into its slice (a shard freed once read when `release`).
  out.resize(n);
  on_threads(threads, [&](std::size_t t) {
    std::vector<std::size_t>& mine = at[t];
    for (std::size_t s = t; s < shards_.size(); s += threads) {
      shards_[s].for_each([&](VoxelKey key, const VoxelData& v) {
        out[mine[(key >> 42) - x.x0]++] = voxel_point(key, v);
      });
      if (release) shards_[s].clear();  // this shard is read: free its memory
    }
  });
  // 4. Each slice sorted by key: bucketed by y, then each (x, y) row sorted by z.
  on_threads(threads, [&](std::size_t t) {
    std::vector<VoxelPoint> scratch;
    std::vector<std::uint32_t> row;
    for (std::size_t i = t; i < slices; i += threads)
      sort_slice(out.data() + start[i], start[i + 1] - start[i], scratch, row);
  });
  return out;
}

PointCloud VoxelMap::to_cloud() const {
  PointCloud cloud;
  const auto voxels = sorted_points();
  cloud.points.resize(voxels.size());
  cloud.colors.resize(voxels.size());
  for (std::size_t i = 0; i < voxels.size(); ++i) {
    cloud.points[i] = voxels[i].point;
    cloud.colors[i] = voxels[i].color();
  }
  return cloud;
}

Vec3 VoxelMap::centroid() const {
  // Summed in fixed point (0.1 µm) so that the sum is exact and does not depend on the visiting
  // order (the hash layout); no sort needed.
  constexpr double kUnit = 1e7;
  std::int64_t sum[3] = {0, 0, 0};
  std::size_t n = 0;
  for_each([&](VoxelKey key, const VoxelData& v) {
    const Vec3 p = mean_position(key, v);
    for (int a = 0; a < 3; ++a) sum[a] += std::llround(p[a] * kUnit);
    ++n;
  });
  if (n == 0) return Vec3::Zero();
  return Vec3(static_cast<double>(sum[0]), static_cast<double>(sum[1]),
              static_cast<double>(sum[2])) /
         (kUnit * static_cast<double>(n));
}

std::size_t common_voxels(const VoxelMap& a, const VoxelMap& b) {
  const VoxelMap& small = a.size() <= b.size() ? a : b;
  const VoxelMap& large = a.size() <= b.size() ? b : a;
  std::size_t n = 0;
  small.for_each([&](VoxelKey key, const VoxelData&) { n += large.contains(key); });
  return n;
}

}  // namespace objmap::fusion
