#pragma once
#include <cstdint>
#include <vector>

#include "objmap/fusion/voxel_map.h"
#include "objmap/geometry/backproject.h"

// One keyframe's dense points summed by voxel straight from its depth image, without a point cloud
// in between: what the keyframe adds to the dense map (VoxelMap::add_shard).
//
// A row's consecutive pixels of one voxel are a run, summed from the row's prefix sums (so neither
// the runs' ends nor their sums cost a branch per pixel); each run is added to its voxel's entry,
// found through a small direct-mapped cache of the voxels met last (a slot per hash of the key), or
// to a new entry when the cache holds another voxel in that slot. A voxel's pixels lie within a
// few rows of each other, so it gets one entry per frame, rarely two, where summing the runs into
// a per-frame hash table costs a probed table update per run (on TUM frames: 236k points, 102k
// runs, 42k voxels, 44k entries).
namespace objmap::fusion {

class FrameVoxels {
 public:
  struct Entry {
    VoxelKey key = geometry::kNoVoxel;
    VoxelData sum;
  };

  // Entries of shard s (0 <= s < shard_count()), in the order they were made (row-major order of
  // their first pixel). The shard of a key is VoxelMap::shard_of's for the map given to
  // frame_voxels().
  const Entry* shard_begin(std::size_t s) const { return shards_[s].data(); }
  const Entry* shard_end(std::size_t s) const { return shards_[s].data() + shards_[s].size(); }
  std::size_t shard_count() const { return shards_.size(); }
  std::size_t entries() const;

  std::uint64_t points() const { return points_; }    // back-projected points (valid depth)
  std::uint64_t dropped() const { return dropped_; }  // of those: not finite / out of key range
  std::size_t pixels_considered() const { return considered_; }
  double voxel_m() const { return voxel_m_; }  // of the map they were made for

 private:
  friend void frame_voxels(const geometry::RayTable&, const geometry::DepthFrame&,
                           const geometry::BackprojectOptions&, const VoxelMap&, FrameVoxels&);
  struct CacheSlot {  // a voxel met lately and its entry
    VoxelKey key = geometry::kNoVoxel;
    std::uint32_t shard = 0, index = 0;
  };
  static constexpr int kCacheBits = 13;  // 8192 slots, 128 KB
  static constexpr std::size_t kCacheSlots = std::size_t{1} << kCacheBits;
  static std::size_t cache_slot(VoxelKey key) {  // Fibonacci hashing: all key bits reach the top
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ULL) >> (64 - kCacheBits));
  }

  std::vector<std::vector<Entry>> shards_;  // entries by shard, each in the order made
  // Scratch kept from one frame to the next (no allocation per frame once warm).
  std::vector<CacheSlot> cache_;
  std::vector<VoxelKey> row_key_;  // the current row: each column's voxel (kNoVoxel: none)
  std::vector<float> row_offset_;  // the current row: offsets in the voxels, x, y, z (0: none)
  std::vector<std::uint32_t> row_start_;         // the current row's runs: first columns
  std::vector<double> row_prefix_;               // prefix sums of row_offset_'s x, y, z
  std::vector<std::uint32_t> row_color_prefix_;  // prefix sums of the colours' r, g, b
  std::uint64_t points_ = 0, dropped_ = 0;
  std::size_t considered_ = 0;
  double voxel_m_ = 0;
};

// Back-projects `frame` as geometry::backproject does (the same points, bit for bit: depth range,
// stride, region, mask and colours as there) and sums them by voxel of `map` (its voxel size and
// shards) into `out`, which is overwritten. Throws InputError as geometry::backproject.
void frame_voxels(const geometry::RayTable& rays, const geometry::DepthFrame& frame,
                  const geometry::BackprojectOptions& options, const VoxelMap& map,
                  FrameVoxels& out);

}  // namespace objmap::fusion
