#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include "objmap/fusion/object_map.h"
#include "objmap/mesh/tsdf.h"

// The meshes of `objmap fuse --mesh`: a TSDF model of every confirmed object, fused from the masked
// points of the observations that joined it (after mask refinement and the depth gate; the
// observations of objects that the merge pass joined are unioned), and optionally one of the whole
// scene from every keyframe's depth (docs/mesh.md).
namespace objmap::pipeline {

struct MeshOptions {
  // none|objects|scene|all (mesh::parse_mesh_selection); off by default: the objects' meshes add
  // ~20% CPU to a fuse of fr1_rpy_every4 (docs/mesh.md, "Cost"), more than the 15% a default may.
  std::string select = "none";
  mesh::TsdfOptions tsdf;        // the objects' models: voxel from the size, carving, weights
  double box_margin_m = 0.02;    // an object's model is its box (AABB) grown by this
  double scene_voxel_m = 0.02;   // the scene model's voxel
  double scene_carving_m = 0.3;  // the scene carves this far in front of each ray's band
  void check() const;            // throws InputError naming the bad field (mesh.*)
};

// An observation's masked points as an object's model keeps them: voxel means at the finest model
// voxel (min_voxel_m, or voxel_m when fixed), so that memory follows the objects' surfaces, not
// their pixels. Made by fuse's workers, in parallel.
PointCloud model_points(const fusion::Observation& obs, const MeshOptions& options);

// The masked points of each observation that joined an object, kept from the fuse for the objects'
// models.
class ObjectViews {
 public:
  // An observation of keyframe `timestamp` seen from `camera_in_world` joined object `object_id`
  // (as it was then; merges and splits are resolved later); `points` from model_points().
  void add(int object_id, double timestamp, const Vec3& camera_in_world, PointCloud&& points);
  std::size_t views() const { return views_.size(); }

  // Views of object `id` after the merge and split passes: those that resolve to it, in the
  // order they were added (keyframe order).
  std::vector<mesh::DepthView> views_of(int id, const fusion::ObjectMap& objects) const;

 private:
  struct View {
    int object_id;
    double timestamp;
    Vec3 camera_in_world;
    PointCloud points;
  };
  std::vector<View> views_;
};

// One object's model, meshed.
struct ObjectMesh {
  int id = -1;
  mesh::ModelResult model;
  std::size_t views = 0;
};

// The models of `records` (confirmed objects), each in its box grown by box_margin_m at the voxel
// its size and the pixels' footprint (a camera of focal length `focal_px`) ask for, on `threads`
// threads; one result per record, in their order.
std::vector<ObjectMesh> mesh_objects(const std::vector<fusion::ObjectRecord>& records,
                                     const ObjectViews& views, const fusion::ObjectMap& objects,
                                     const MeshOptions& options, double focal_px, int threads);

// The box of a whole scene's model: space itself (nothing is clipped).
Aabb unbounded_box();

// The scene model's options: the objects' rules at scene_voxel_m, carving scene_carving_m deep.
mesh::TsdfOptions scene_tsdf_options(const MeshOptions& options);

}  // namespace objmap::pipeline
