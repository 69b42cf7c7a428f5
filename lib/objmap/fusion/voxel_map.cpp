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
// (neighbouring pixels) are summed locally and written with one hash access. Returns the number of
// points dropped (not finite or out of range).
std::size_t VoxelMap::insert_shard(std::size_t shard, const PointCloud& cloud, std::int32_t label) {
  Table& table = shards_[shard];
  const bool colour = cloud.has_colors();
  const bool sharded = shards_.size() > 1;
  const std::size_t n = cloud.size();
  std::size_t dropped = 0;
  VoxelKey run_key = kNoVoxel;
  bool run_ours = false;
  VoxelData run;
  auto flush = [&]() {
    if (run_key == kNoVoxel || !run_ours) return;
    VoxelData& v = table[run_key];
    for (int a = 0; a < 3; ++a) {
      v.offset_sum[a] += run.offset_sum[a];
      v.color_sum[a] += run.color_sum[a];
    }
    v.count += run.count;
    v.color_count += run.color_count;
    vote(v, label, static_cast<std::int32_t>(run.count));
  };
  Eigen::Vector3i ijk;
  Eigen::Vector3f offset;
  for (std::size_t i = 0; i < n; ++i) {
    if (!geometry::voxel_coords(cloud.points[i], inv_voxel_m_, ijk, offset)) {
      ++dropped;
      continue;
    }
    const VoxelKey key = geometry::pack_voxel(ijk.x(), ijk.y(), ijk.z());
    if (key != run_key) {
      flush();
      run_key = key;
      run_ours = !sharded || shard_of(key) == shard;
      run = VoxelData{};
    }
    if (!run_ours) continue;
    run.offset_sum[0] += offset.x();
    run.offset_sum[1] += offset.y();
    run.offset_sum[2] += offset.z();
    ++run.count;
    if (colour) {
      const Rgb& c = cloud.colors[i];
      run.color_sum[0] += c.r;
      run.color_sum[1] += c.g;
      run.color_sum[2] += c.b;
      ++run.color_count;
    }
  }
  flush();
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
          "voxel sizes differ (" + std::to_string(other.voxel_m_) + " vs " + std::to_string(voxel_m_) +
              "); expected equal");
  // Each voxel of `other` is added once, so the visiting order changes no voxel's value (only the
  // hash layout, which no export depends on).
  other.for_each([&](VoxelKey key, const VoxelData& src) {
    VoxelData& v = shards_[shard_of(key)][key];
    for (int a = 0; a < 3; ++a) {
      v.offset_sum[a] += src.offset_sum[a];
      v.color_sum[a] += src.color_sum[a];
    }
    v.count += src.count;
    v.color_count += src.color_count;
    vote(v, src.label, src.label_votes);
  });
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
  std::sort(out.begin(), out.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
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
  const auto voxels = sorted_voxels();  // sorted: the sum does not depend on the hash layout
  if (voxels.empty()) return Vec3::Zero();
  Vec3 sum = Vec3::Zero();
  for (const auto& [key, v] : voxels) sum += mean_position(key, *v);
  return sum / static_cast<double>(voxels.size());
}

std::size_t common_voxels(const VoxelMap& a, const VoxelMap& b) {
  const VoxelMap& small = a.size() <= b.size() ? a : b;
  const VoxelMap& large = a.size() <= b.size() ? b : a;
  std::size_t n = 0;
  small.for_each([&](VoxelKey key, const VoxelData&) { n += large.contains(key); });
  return n;
}

}  // namespace objmap::fusion
