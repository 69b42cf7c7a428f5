#pragma once
#include <memory>

#include "objmap/pipeline/dense_cloud.h"

namespace objmap::fusion {
class VoxelMap;
}

// A live dense map's cloud kept up to date between publishes (objmap follow): rather than copying
// and sorting every voxel at each publish, the voxels the map touched since the last update
// (VoxelMap::track_touched) are folded into the cloud of the last one, in one merge pass. The
// cloud equals take_dense_cloud() of the map at the time of the update.
namespace objmap::pipeline {

class DenseSnapshot {
 public:
  // Starts tracking `map`'s changes (from empty: the map must be empty now).
  explicit DenseSnapshot(fusion::VoxelMap& map);

  // `map`'s cloud now (sorted by key, as take_dense_cloud gives it); the cloud handed out before
  // stays as it was. `map` is the one tracked; nothing may change it meanwhile.
  std::shared_ptr<const DenseCloud> update(fusion::VoxelMap& map);

  std::size_t last_touched() const { return last_touched_; }  // distinct voxels of the update

 private:
  std::shared_ptr<DenseCloud> cloud_;  // handed out as const; changed when no publish reads it
  std::size_t last_touched_ = 0;
};

}  // namespace objmap::pipeline
