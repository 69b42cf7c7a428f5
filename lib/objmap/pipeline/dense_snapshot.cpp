#include "objmap/pipeline/dense_snapshot.h"

#include <algorithm>
#include <array>

#include "objmap/core/error.h"
#include "objmap/fusion/voxel_map.h"

namespace objmap::pipeline {

namespace {

using fusion::VoxelKey;
using VoxelPoint = fusion::VoxelMap::VoxelPoint;

void put(DenseCloud& c, std::size_t at, const VoxelPoint& p) {
  c.keys[at] = p.key;
  c.cloud.points[at] = p.point;
  c.cloud.colors[at] = p.color();
}

// The cloud without the `gone` keys (sorted).
void drop_gone(DenseCloud& c, const std::vector<VoxelKey>& gone) {
  std::vector<char> drop(c.keys.size(), 0);
  std::size_t g = 0;
  for (std::size_t i = 0; i < c.keys.size(); ++i) {
    while (g < gone.size() && gone[g] < c.keys[i]) ++g;
    drop[i] = g < gone.size() && gone[g] == c.keys[i];
  }
  drop_points(c, drop);
}

}  // namespace

// Room for this many voxels in the cloud's arrays from the start. Blocks this large are mapped by
// the allocator (core/memory.h: above 32 MB), and their pages become memory only as they are
// written: the arrays grow without being copied (a copy holds the old and the new array at once:
// 12 bytes a voxel more for the points, 116 MB at walk1200's 9.7 M voxels) until the map has
// this many voxels, then by doubling. Address space only: 23 bytes a voxel, 770 MB.
constexpr std::size_t kReservedVoxels = std::size_t{1} << 25;

DenseSnapshot::DenseSnapshot(fusion::VoxelMap& map) : cloud_(std::make_shared<DenseCloud>()) {
  require(map.size() == 0, "DenseSnapshot", "the map has voxels; expected an empty map to follow");
  map.track_touched();
  cloud_->keys.reserve(kReservedVoxels);
  cloud_->cloud.points.reserve(kReservedVoxels);
  cloud_->cloud.colors.reserve(kReservedVoxels);
}

std::shared_ptr<const DenseCloud> DenseSnapshot::update(fusion::VoxelMap& map) {
  return apply(take(map));
}

DenseChanges DenseSnapshot::take(fusion::VoxelMap& map) const {
  // The voxels touched since the last take (once each), with their points now; each key's slot
  // prefetched kAhead keys before it is read (cache misses overlap), without a list of the keys.
  DenseChanges changes;
  changes.points.reserve(map.touched_count());
  constexpr std::size_t kAhead = 8;
  std::array<VoxelKey, kAhead> ahead;
  std::size_t met = 0;
  auto read = [&](VoxelKey key) {
    if (const fusion::VoxelData* voxel = map.find(key))
      changes.points.push_back(map.voxel_point(key, *voxel));
    else
      changes.gone.push_back(key);
  };
  map.take_touched([&](VoxelKey key) {
    map.prefetch(key);
    if (met >= kAhead) read(ahead[met % kAhead]);
    ahead[met++ % kAhead] = key;
  });
  for (std::size_t k = met > kAhead ? met - kAhead : 0; k < met; ++k) read(ahead[k % kAhead]);
  return changes;
}

std::shared_ptr<const DenseCloud> DenseSnapshot::apply(DenseChanges changes) {
  // 1. The changed voxels (once each) in key order.
  std::vector<VoxelPoint>& points = changes.points;
  std::sort(points.begin(), points.end(),
            [](const VoxelPoint& a, const VoxelPoint& b) { return a.key < b.key; });
  std::vector<VoxelKey>& gone = changes.gone;
  std::sort(gone.begin(), gone.end());
  last_touched_ = points.size() + gone.size();
  if (last_touched_ == 0) return cloud_;
  // 2. The cloud changed in place, unless a publish still reads it.
  if (cloud_.use_count() > 1) cloud_ = std::make_shared<DenseCloud>(*cloud_);
  DenseCloud& c = *cloud_;
  if (!gone.empty()) drop_gone(c, gone);
  // 3. The voxels the cloud has take their points now; the new ones are moved, in their order, to
  //    the front of `points`, then merged into the cloud from the back (one pass each, no second
  //    copy of the cloud, no list of them).
  const std::size_t n = c.keys.size();
  std::size_t fresh = 0, i = 0;
  for (std::size_t j = 0; j < points.size(); ++j) {
    while (i < n && c.keys[i] < points[j].key) ++i;
    if (i < n && c.keys[i] == points[j].key)
      put(c, i, points[j]);
    else
      points[fresh++] = points[j];
  }
  if (fresh == 0) return cloud_;
  c.keys.resize(n + fresh);
  c.cloud.points.resize(n + fresh);
  c.cloud.colors.resize(n + fresh);
  std::size_t old = n, w = n + fresh;
  for (std::size_t f = fresh; f-- > 0;) {
    const VoxelPoint& p = points[f];
    for (; old > 0 && c.keys[old - 1] > p.key; --w, --old) {
      c.keys[w - 1] = c.keys[old - 1];
      c.cloud.points[w - 1] = c.cloud.points[old - 1];
      c.cloud.colors[w - 1] = c.cloud.colors[old - 1];
    }
    put(c, --w, p);
  }
  return cloud_;
}

}  // namespace objmap::pipeline
