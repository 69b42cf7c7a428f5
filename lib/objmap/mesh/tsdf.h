#pragma once
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "objmap/core/mesh.h"
#include "objmap/core/types.h"

// Truncated signed-distance models (a sparse OpenVDB grid, private to this module) fused from depth
// observations, and their surface by marching cubes. One model per object, fused from the masked
// pixels of the observations that joined it (the pixels fuse keeps after mask refinement and the
// depth gate), and optionally one of the whole scene.
namespace objmap::mesh {

// "none", "objects", "scene" or "all": which meshes `objmap fuse --mesh` makes.
struct MeshSelection {
  bool objects = false;
  bool scene = false;
};
MeshSelection parse_mesh_selection(const std::string& text, const std::string& where);

struct TsdfOptions {
  // The voxel: `voxel_m` when > 0, else voxel_fraction × the object's largest box side, clamped
  // to [min_voxel_m, max_voxel_m] (docs/mesh.md measures the choices).
  double voxel_m = 0.0;
  double voxel_fraction = 0.02;  // 1/50 of the extent (Khronos: 2%)
  double min_voxel_m = 0.004;    // 4 mm: below it depth noise, not the voxel, limits the surface
  double max_voxel_m = 0.02;     // 2 cm
  // ... and at least this many pixels' footprint at the object's median depth: every view must put
  // a ray into most voxels of the surface it sees, or the model has holes between the rays.
  double min_voxel_pixels = 1.5;
  double truncation_voxels = 3.0;  // the band ±truncation around each measured depth, in voxels
  double min_truncation_m =
      0.01;  // ... and at least this (depth noise of a structured-light camera)
  // Space carving: the free space along each ray in front of the band (inside the model's box) is
  // fused as "empty", so that bleed and flying pixels that other views see through are carved.
  bool space_carving = true;
  double carving_depth_m = 0.0;  // carve this far in front of the band; 0: to the box's side
  // A ray's weight is (sigma(reference_depth_m) / sigma(z))^2 with the structured-light noise
  // sigma(z) = 0.0012 + 0.0019 (z - 0.4)^2 m (Nguyen et al. 2012); z the depth along the ray.
  double reference_depth_m = 1.0;
  // Marching cubes keeps a vertex only where every voxel of its cell carries at least this weight
  // (in units of one ray at reference_depth_m): no surface against unobserved space. 0.005 is one
  // ray at 4 m, the farthest depth fused: observed at all (0.5 dropped the far half of a room).
  double min_weight = 0.005;
  // Triangles in connected pieces smaller than this share of the mesh's triangles are dropped
  // (floaters of a single view).
  double min_component_share = 0.02;
  void check() const;  // throws InputError naming the bad field
};

// One observation: the camera's centre and the points it measured (world frame, colours
// optional). Each point is a ray from the centre through it.
struct DepthView {
  Vec3 camera_in_world = Vec3::Zero();
  const PointCloud* points = nullptr;
};

struct ModelResult {
  TriangleMesh mesh;  // vertex normals (outward: toward the free space) and colours
  double voxel_m = 0.0;
  double truncation_m = 0.0;
  std::size_t voxels = 0;  // active voxels of the model
  std::size_t rays = 0;    // rays fused (one per view and voxel: each view's points are
                           // averaged per voxel first)
};

// The voxel size of a model whose box has sides `box_size` (metres) under `options`; with
// `pixel_footprint_m` (a pixel's size at the views' median depth, > 0) at least min_voxel_pixels of
// it (a fixed voxel_m is taken as it is).
double model_voxel_m(const Vec3& box_size, const TsdfOptions& options,
                     double pixel_footprint_m = 0.0);

// A pixel's footprint at the median distance of the views' points from their cameras, for a camera
// of focal length `focal_px` pixels.
double pixel_footprint_m(const std::vector<DepthView>& views, double focal_px);

// One view's points averaged per voxel of `voxel_m` (mean position and colour), in the order the
// voxels are first met: the rays a model fuses from the view (one per voxel and view; a surface 1 m
// away holds ~20 pixels per 4 mm voxel, all telling the same).
PointCloud voxel_means(const PointCloud& points, double voxel_m);

// A TSDF restricted to a box (nothing outside it is stored) at one voxel size, fused view by view
// (VDBFusion's integration: each ray's band ±truncation, and with space carving the free space in
// front of it), then meshed. Deterministic for a given order of views.
class TsdfModel {
 public:
  TsdfModel(const Aabb& box, double voxel_m, const TsdfOptions& options);
  ~TsdfModel();
  TsdfModel(TsdfModel&&) noexcept;
  TsdfModel& operator=(TsdfModel&&) noexcept;
  void add(const DepthView& view);
  // The zero level by marching cubes (OpenVDB volumeToMesh), with the weight and component rules
  // of the options.
  ModelResult mesh() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Loads the OpenVDB module that TsdfModel uses (libobjmap_vdb.so, loaded once, the first time a
// model is made); throws InputError naming the places tried when it cannot. A command that will
// make meshes calls it before it writes anything.
void require_meshes();

// A TsdfModel of `views` in their order, meshed. Empty views give an empty mesh.
ModelResult fuse_model(const std::vector<DepthView>& views, const Aabb& box, double voxel_m,
                       const TsdfOptions& options);

}  // namespace objmap::mesh
