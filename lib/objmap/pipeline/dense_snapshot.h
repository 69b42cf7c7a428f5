#pragma once
#include <memory>
#include <vector>

#include "objmap/fusion/voxel_map.h"
#include "objmap/pipeline/dense_cloud.h"

// A live dense map's cloud kept up to date between publishes (objmap follow): rather than copying
// and sorting every voxel at each publish, the voxels the map touched since the last update
// (VoxelMap::track_touched) are folded into the cloud of the last one, in one merge pass. The
// cloud equals take_dense_cloud() of the map at the time of the update.
namespace objmap::pipeline {

// What the map changed since the last take: the touched voxels' points as they are now (in no
// order, each voxel once) and the touched voxels it no longer has.
struct DenseChanges {
  std::vector<fusion::VoxelMap::VoxelPoint> points;
  std::vector<fusion::VoxelKey> gone;
};

class DenseSnapshot {
 public:
  // Starts tracking `map`'s changes (from empty: the map must be empty now).
  explicit DenseSnapshot(fusion::VoxelMap& map);

  // `map`'s cloud now (sorted by key, as take_dense_cloud gives it); the cloud handed out before
  // stays as it was. `map` is the one tracked; nothing may change it meanwhile. apply(take(map)).
  std::shared_ptr<const DenseCloud> update(fusion::VoxelMap& map);
  // The two halves of update: on the map's thread, what changed since the last take (nothing may
  // change the map meanwhile); then, on any thread, the cloud with them folded in. The changes
  // are applied one take at a time, in their order; a take may run beside the apply before it.
  DenseChanges take(fusion::VoxelMap& map) const;
  std::shared_ptr<const DenseCloud> apply(DenseChanges changes);

  std::size_t last_touched() const { return last_touched_; }  // distinct voxels of the apply

 private:
  std::shared_ptr<DenseCloud> cloud_;  // handed out as const; changed when no publish reads it
  std::size_t last_touched_ = 0;
};

}  // namespace objmap::pipeline
