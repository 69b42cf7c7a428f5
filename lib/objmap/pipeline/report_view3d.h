#pragma once
// What `objmap report` puts into the page's 3D view (lib/objmap/report/view3d.h), gathered from
// the run: the scene (surfaces, relations) and the answers of `objmap query` to every phrase the
// map's classes make.
#include <optional>
#include <vector>

#include "objmap/core/mesh.h"
#include "objmap/core/types.h"
#include "objmap/io/objects_json.h"
#include "objmap/io/scene_json.h"
#include "objmap/report/view3d.h"

namespace objmap::pipeline {

struct View3dInputs {
  const std::vector<io::MappedObject>* objects = nullptr;  // objects.json, world frame
  std::vector<int> views;                                  // per object: view_count (0: none)
  std::vector<PointCloud> clouds;                          // per object: its PLY, world frame
  std::vector<TriangleMesh> meshes;  // per object: its mesh (world frame), empty where none
  PointCloud map;                    // already in the gravity frame
  std::size_t map_points_total = 0;  // before thinning
  double map_point_size_m = 0.01;
  std::vector<Vec3> camera_path;                      // world frame
  std::optional<io::SceneDescription> scene;          // none: a run without the scene fields
  std::optional<Eigen::Matrix3d> gravity_from_world;  // none: the world is z up
};

report::View3dContent view3d_content(View3dInputs inputs);

// Every phrase "CLASS" and "CLASS RELATION TARGET" of the map's classes and the ids that
// scene::run_query matches for it (only phrases with a match).
std::map<std::string, std::vector<int>> all_query_matches(const io::SceneDescription& scene);

}  // namespace objmap::pipeline
