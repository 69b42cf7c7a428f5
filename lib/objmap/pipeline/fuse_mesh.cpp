#include "objmap/pipeline/fuse_mesh.h"

#include <cmath>

#include "objmap/core/error.h"
#include "objmap/core/parallel.h"

namespace objmap::pipeline {

void MeshOptions::check() const {
  mesh::parse_mesh_selection(select, "mesh.select");
  try {
    tsdf.check();
  } catch (const InputError& e) {
    throw InputError("mesh." + e.where(), e.reason());
  }
  require(std::isfinite(box_margin_m) && box_margin_m >= 0.0 && box_margin_m <= 1.0,
          "mesh.box_margin_m", "must be in [0, 1] m");
  require(std::isfinite(scene_voxel_m) && scene_voxel_m >= 0.002 && scene_voxel_m <= 0.5,
          "mesh.scene_voxel_m", "must be in [0.002, 0.5] m");
  require(std::isfinite(scene_carving_m) && scene_carving_m >= 0.0, "mesh.scene_carving_m",
          "must be >= 0 m");
}

PointCloud model_points(const fusion::Observation& obs, const MeshOptions& options) {
  const double finest = options.tsdf.voxel_m > 0 ? options.tsdf.voxel_m : options.tsdf.min_voxel_m;
  return mesh::voxel_means(obs.points_in_world, finest);
}

void ObjectViews::add(int object_id, double timestamp, const Vec3& camera_in_world,
                      PointCloud&& points) {
  views_.push_back({object_id, timestamp, camera_in_world, std::move(points)});
}

std::vector<mesh::DepthView> ObjectViews::views_of(int id, const fusion::ObjectMap& objects) const {
  std::vector<mesh::DepthView> out;
  for (const View& v : views_)
    if (objects.resolve(v.object_id, v.timestamp) == id)
      out.push_back({v.camera_in_world, &v.points});
  return out;
}

std::vector<ObjectMesh> mesh_objects(const std::vector<fusion::ObjectRecord>& records,
                                     const ObjectViews& views, const fusion::ObjectMap& objects,
                                     const MeshOptions& options, double focal_px, int threads) {
  std::vector<ObjectMesh> out(records.size());
  parallel_for(records.size(), threads, [&](std::size_t i) {
    const fusion::ObjectRecord& r = records[i];
    Aabb box = r.aabb;
    box.min -= Vec3::Constant(options.box_margin_m);
    box.max += Vec3::Constant(options.box_margin_m);
    const std::vector<mesh::DepthView> object_views = views.views_of(r.id, objects);
    const double voxel = mesh::model_voxel_m(r.aabb.max - r.aabb.min, options.tsdf,
                                             mesh::pixel_footprint_m(object_views, focal_px));
    out[i].id = r.id;
    out[i].views = object_views.size();
    out[i].model = mesh::fuse_model(object_views, box, voxel, options.tsdf);
  });
  return out;
}

Aabb unbounded_box() {
  Aabb box;
  box.min = Vec3::Constant(-1e4);
  box.max = Vec3::Constant(1e4);
  return box;
}

mesh::TsdfOptions scene_tsdf_options(const MeshOptions& options) {
  mesh::TsdfOptions o = options.tsdf;
  o.voxel_m = options.scene_voxel_m;
  o.carving_depth_m = options.scene_carving_m;
  o.min_component_share = 0.0005;
  return o;
}

}  // namespace objmap::pipeline
