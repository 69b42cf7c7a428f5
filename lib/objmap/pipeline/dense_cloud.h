#pragma once
#include <cstddef>
#include <vector>

#include "objmap/core/types.h"
#include "objmap/fusion/object_map.h"
#include "objmap/fusion/voxel_map.h"

// The dense map as the cloud of map_dense.ply and map_semantic.ply, after the keyframes of a fuse.
namespace objmap::pipeline {

// The dense map as a cloud (map_dense.ply): one point per voxel at its mean position with its mean
// colour, sorted by voxel key, and the keys (for the semantic colours). Frees the map.
struct DenseCloud {
  PointCloud cloud;
  std::vector<fusion::VoxelKey> keys;
};

DenseCloud take_dense_cloud(fusion::VoxelMap& dense, const fusion::VoxelMapOptions& options);

// The semantic colours of the dense points (map_semantic.ply), as fusion::make_semantic_maps: a
// voxel holding a point of a confirmed object takes that object's class colour (its owner in
// fusion::voxel_owners), the others keep their mean colour.
std::vector<Rgb> semantic_colors(const DenseCloud& dense, double voxel_m,
                                 const std::vector<fusion::ObjectRecord>& records,
                                 const std::vector<Rgb>& record_color);

// Removes the points whose `drop` flag is set (one per point), keeping the order; returns how many.
std::size_t drop_points(DenseCloud& dense, const std::vector<char>& drop);

// Leaves out of the dense map (and so of the semantic map) the voxels that hold a point of a
// sighting and of no map object: what moved is not the map. Its voxels of the keyframes where it
// was not detected stay. Returns the voxels left out.
std::size_t drop_sighting_voxels(DenseCloud& dense,
                                 const std::vector<fusion::ObjectRecord>& sightings,
                                 const std::vector<fusion::ObjectRecord>& objects, double voxel_m);

}  // namespace objmap::pipeline
