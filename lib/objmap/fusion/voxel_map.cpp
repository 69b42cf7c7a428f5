#include "objmap/fusion/voxel_map.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <thread>

#include "objmap/core/error.h"

namespace objmap::fusion {

using geometry::kNoVoxel;

void VoxelMapOptions::check() const {
  require(std::isfinite(voxel_m) && voxel_m >= 1e-4 && voxel_m <= 100.0, "VoxelMapOptions.voxel_m",
          "must be in [0.0001, 100] metres, got " + std::to_string(voxel_m));
  require(threads >= 1 && threads <= 64, "VoxelMapOptions.threads",
          "must be in [1, 64], got " + std::to_string(threads));
}

Rgb VoxelData::mean_color() const {
  if (color_count == 0) return {128, 128, 128};
  auto avg = [&](std::uint32_t s) {
    return static_cast<std::uint8_t>((s + color_count / 2) / color_count);
  };
  return {avg(color_sum[0]), avg(color_sum[1]), avg(color_sum[2])};
}

namespace {

// `n` votes for `label` on a Boyer-Moore majority counter.
void vote(VoxelData& v, std::int32_t label, std::int32_t n) {
  if (label == kNoLabel || n <= 0) return;
  if (v.label == label) {
    v.label_votes += n;
  } else if (v.label_votes >= n) {
    v.label_votes -= n;
  } else {
    v.label = label;
    v.label_votes = n - v.label_votes;
  }
}

}  // namespace

VoxelMap::VoxelMap(const VoxelMapOptions& options) {
  options.check();
  voxel_m_ = options.voxel_m;
  inv_voxel_m_ = static_cast<float>(1.0 / options.voxel_m);
  shards_.resize(static_cast<std::size_t>(options.threads));
}

std::size_t VoxelMap::shard_of(VoxelKey key) const {
  return shards_.size() == 1 ? 0 : geometry::mix_voxel_key(key) % shards_.size();
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
std::size_t VoxelMap::insert_shard(std::size_t shard, const PointCloud& cloud, std::int32_t label) {
  constexpr std::size_t kBatch = 1024;  // points per batch
  constexpr std::size_t kAhead = 12;    // runs prefetched ahead
  struct Run {
    VoxelKey key;
    VoxelData sum;
  };
  Table& table = shards_[shard];
  const bool colour = cloud.has_colors();
  const bool sharded = shards_.size() > 1;
  const std::size_t n = cloud.size();
  std::size_t dropped = 0;
  std::vector<Run> runs;
  runs.reserve(kBatch);
  std::vector<std::int32_t> cell(3 * kBatch);
  std::vector<float> frac(3 * kBatch);
  std::vector<std::uint8_t> valid(kBatch);
  constexpr float lim = static_cast<float>(geometry::kVoxelCoordLimit);
  for (std::size_t begin = 0; begin < n; begin += kBatch) {
    const std::size_t end = std::min(n, begin + kBatch);
    // 1. Voxel coordinates and in-voxel offsets of the batch (a branch-free, vectorisable loop).
    const std::size_t count = end - begin;
    for (std::size_t j = 0; j < count; ++j) {
      const Vec3f& p = cloud.points[begin + j];
      float sx = p.x() * inv_voxel_m_, sy = p.y() * inv_voxel_m_, sz = p.z() * inv_voxel_m_;
      const bool ok = sx >= -lim && sx < lim && sy >= -lim && sy < lim && sz >= -lim && sz < lim;
      if (!ok) sx = sy = sz = 0.f;  // no float-to-int conversion of NaN or huge values
      const std::int32_t ix = geometry::fast_floor(sx), iy = geometry::fast_floor(sy),
                         iz = geometry::fast_floor(sz);
      cell[3 * j] = ix;
      cell[3 * j + 1] = iy;
      cell[3 * j + 2] = iz;
      frac[3 * j] = sx - static_cast<float>(ix);
      frac[3 * j + 1] = sy - static_cast<float>(iy);
      frac[3 * j + 2] = sz - static_cast<float>(iz);
      valid[j] = ok;
    }
    // 2. The batch's runs of consecutive points in one voxel (only this shard's voxels).
    runs.clear();
    VoxelKey run_key = kNoVoxel;
    bool run_ours = false;
    for (std::size_t j = 0; j < count; ++j) {
      if (!valid[j]) {
        ++dropped;
        continue;
      }
      const VoxelKey key = geometry::pack_voxel(cell[3 * j], cell[3 * j + 1], cell[3 * j + 2]);
      if (key != run_key) {
        run_key = key;
        run_ours = !sharded || shard_of(key) == shard;
        if (run_ours) runs.push_back(Run{key, VoxelData{}});
      }
      if (!run_ours) continue;
      VoxelData& r = runs.back().sum;
      r.offset_sum[0] += frac[3 * j];
      r.offset_sum[1] += frac[3 * j + 1];
      r.offset_sum[2] += frac[3 * j + 2];
      ++r.count;
      if (colour) {
        const Rgb& c = cloud.colors[begin + j];
        r.color_sum[0] += c.r;
        r.color_sum[1] += c.g;
        r.color_sum[2] += c.b;
        ++r.color_count;
      }
    }
    // 3. The runs into the table, in order, prefetching ahead.
    table.reserve(table.size() + runs.size());  // no rehash below: prefetched slots stay valid
    const std::size_t m = runs.size();
    for (std::size_t r = 0; r < std::min(m, kAhead); ++r) table.prefetch(runs[r].key);
    for (std::size_t r = 0; r < m; ++r) {
      if (r + kAhead < m) table.prefetch(runs[r + kAhead].key);
      const VoxelData& add = runs[r].sum;
      VoxelData& v = table[runs[r].key];
      for (int a = 0; a < 3; ++a) {
        v.offset_sum[a] += add.offset_sum[a];
        v.color_sum[a] += add.color_sum[a];
      }
      v.count += add.count;
      v.color_count += add.color_count;
      vote(v, label, static_cast<std::int32_t>(add.count));
    }
  }
  return dropped;
}

void VoxelMap::insert(const PointCloud& cloud, std::int32_t label) {
  const std::size_t n = cloud.size();
  if (n == 0) return;
  const std::size_t threads = shards_.size();
  // Every shard scans all points and adds those of its voxels (shards in parallel).
  std::size_t dropped = 0;
  if (threads == 1 || n < 4096) {
    for (std::size_t s = 0; s < threads; ++s) dropped = insert_shard(s, cloud, label);
  } else {
    std::vector<std::thread> pool;
    for (std::size_t t = 1; t < threads; ++t)
      pool.emplace_back([&, t] { insert_shard(t, cloud, label); });
    dropped = insert_shard(0, cloud, label);
    for (auto& th : pool) th.join();
  }
  points_inserted_ += n - dropped;
  points_dropped_ += dropped;
}

void VoxelMap::merge(const VoxelMap& other) {
  require(other.voxel_m_ == voxel_m_, "VoxelMap::merge",
          "voxel sizes differ (" + std::to_string(other.voxel_m_) + " vs " +
              std::to_string(voxel_m_) + "); expected equal");
  // Each voxel of `other` is added once, so the visiting order changes no voxel's value (only the
  // hash layout, which no export depends on). Slots of a later voxel are prefetched, as in
  // insert().
  constexpr std::size_t kAhead = 12;
  std::vector<std::pair<VoxelKey, const VoxelData*>> todo;
  todo.reserve(other.size());
  other.for_each([&](VoxelKey key, const VoxelData& v) { todo.emplace_back(key, &v); });
  if (shards_.size() == 1) shards_[0].reserve(shards_[0].size() + todo.size());
  for (std::size_t r = 0; r < todo.size(); ++r) {
    if (shards_.size() == 1 && r + kAhead < todo.size())
      shards_[0].prefetch(todo[r + kAhead].first);
    const VoxelKey key = todo[r].first;
    const VoxelData& src = *todo[r].second;
    VoxelData& v = shards_[shard_of(key)][key];
    for (int a = 0; a < 3; ++a) {
      v.offset_sum[a] += src.offset_sum[a];
      v.color_sum[a] += src.color_sum[a];
    }
    v.count += src.count;
    v.color_count += src.color_count;
    vote(v, src.label, src.label_votes);
  }
  points_inserted_ += other.points_inserted_;
  points_dropped_ += other.points_dropped_;
}

bool VoxelMap::key_bounds(Eigen::Vector3i& lo, Eigen::Vector3i& hi) const {
  bool any = false;
  for (const Table& t : shards_) {
    t.for_each([&](VoxelKey key, const VoxelData&) {
      const Eigen::Vector3i ijk = geometry::unpack_voxel(key);
      if (!any) {
        lo = hi = ijk;
        any = true;
      } else {
        lo = lo.cwiseMin(ijk);
        hi = hi.cwiseMax(ijk);
      }
    });
  }
  return any;
}

std::vector<std::pair<VoxelKey, const VoxelData*>> VoxelMap::sorted_voxels() const {
  std::vector<std::pair<VoxelKey, const VoxelData*>> out;
  out.reserve(size());
  for (const Table& t : shards_)
    t.for_each([&](VoxelKey key, const VoxelData& v) { out.emplace_back(key, &v); });
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return out;
}

PointCloud VoxelMap::to_cloud() const {
  PointCloud cloud;
  const auto voxels = sorted_voxels();
  cloud.reserve(voxels.size());
  for (const auto& [key, v] : voxels)
    cloud.push_back(mean_position(key, *v).cast<float>(), v->mean_color());
  return cloud;
}

PointCloud VoxelMap::to_labelled_cloud(const std::map<std::int32_t, Rgb>& color_of_label,
                                       bool keep_unlabelled) const {
  PointCloud cloud;
  const auto voxels = sorted_voxels();
  cloud.reserve(voxels.size());
  for (const auto& [key, v] : voxels) {
    const auto it = v->label == kNoLabel ? color_of_label.end() : color_of_label.find(v->label);
    if (it != color_of_label.end())
      cloud.push_back(mean_position(key, *v).cast<float>(), it->second);
    else if (keep_unlabelled)
      cloud.push_back(mean_position(key, *v).cast<float>(), v->mean_color());
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
