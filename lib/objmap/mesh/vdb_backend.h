#pragma once
#include <cstdint>

#include "objmap/core/mesh.h"
#include "objmap/core/types.h"
#include "objmap/mesh/tsdf.h"

// The OpenVDB side of the TSDF models (private to this folder). It is built as a module of its own,
// libobjmap_vdb.so (tsdf_vdb.cpp), that TsdfModel loads the first time a model is made: OpenVDB and
// its libraries cost ~50 ms at the start of every command that links them, and only the commands
// that make meshes use them (docs/architecture.md, "Start-up").
namespace objmap::mesh::detail {

// floor() without the library call (the hot loops of voxel_means and the rays' fusion).
inline std::int64_t fast_floor(double x) {
  const auto i = static_cast<std::int64_t>(x);
  return i - (x < static_cast<double>(i));
}

// Raised whenever the table below changes: a module of another build is refused.
constexpr int kVdbBackendAbi = 1;

// What the module serves: a model's life, its rays (one view's voxel means, world frame, colours
// optional) and its mesh. Built by the same compiler as objmap, so C++ types and exceptions cross.
struct VdbBackend {
  int abi = kVdbBackendAbi;
  void* (*create)(const Aabb& box, double voxel_m, const TsdfOptions& options) = nullptr;
  void (*destroy)(void* model) = nullptr;
  void (*add)(void* model, const Vec3& camera_in_world, const PointCloud& rays) = nullptr;
  void (*mesh)(const void* model, ModelResult& out) = nullptr;
};

}  // namespace objmap::mesh::detail

// The module's one exported symbol.
extern "C" const objmap::mesh::detail::VdbBackend* objmap_vdb_backend();
