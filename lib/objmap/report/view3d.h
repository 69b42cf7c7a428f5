#pragma once
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "objmap/core/types.h"
#include "objmap/report/topview.h"

// The report's interactive 3D view (three.js, inlined: report.html works offline from the file
// system): the semantic map thinned to what a browser draws smoothly, every object's points in its
// class colour with its oriented box and label, the support surfaces and the camera path; orbit,
// pan, zoom; a click on an object opens its panel; layer toggles; a search field with the grammar
// of `objmap query`. Everything is in the run's gravity frame (z up, as gravity_from_world makes
// it). The caller gathers the content (apps/objmap/report.cpp); this renders it.
namespace objmap::report {

struct View3dObject {
  int id = -1;  // unique in the view (the diff view gives the after run's objects ids < 0)
  std::string class_name;
  std::string label;  // drawn above it and heading its panel; empty: "id class"
  Rgb color;
  Obb obb;               // in the gravity frame
  int observations = 0;  // objects.json observation_count
  int views = 0;         // view_count (0: not in the file)
  double score = 0.0;
  std::vector<Vec3f> points;  // its PLY's points in the gravity frame (thinned when drawn)
  // What it relates to, one line each, e.g. "on surface 2 (table), gap 0.004 m",
  // "near 5 (keyboard), 0.21 m".
  std::vector<std::string> relations;
  // Room for a mesh (objects/<id>_<class>_mesh.ply) once runs carry one: the viewer draws it
  // instead of the points when `mesh_triangles` is not empty.
  std::vector<Vec3f> mesh_vertices;
  std::vector<int> mesh_triangles;  // 3 vertex indices per triangle
};

struct View3dSurface {
  int id = 0;
  std::string label;                    // floor, table, seat, surface
  std::optional<double> above_floor_m;  // none: no floor found
  std::vector<Vec3> outline;            // in the gravity frame, cyclic
};

// An arrow from one point to another (the diff view: a moved object's old and new place).
struct View3dArrow {
  Vec3 from = Vec3::Zero(), to = Vec3::Zero();  // gravity frame
  Rgb color{220, 30, 30};
  std::string label;  // e.g. "3 cup moved 0.42 m"
};

struct View3dContent {
  PointCloud map;  // the semantic map in the gravity frame, with colours (may be thinned already)
  std::size_t map_points_total = 0;  // the map's points before any thinning (0: map.size())
  std::vector<View3dObject> objects;
  std::vector<View3dSurface> surfaces;
  // A second map drawn beside the first in a layer of its own ("after"; objmap report --diff: the
  // after run's map registered into the before run's frame, tinted); empty: none.
  PointCloud second_map;
  std::size_t second_map_points_total = 0;
  std::vector<View3dArrow> arrows;  // layer "arrows"; none: no such layer
  // The caption under the view; empty: the run report's (the semantic map, objects, surfaces).
  std::string caption;
  std::vector<Vec3> camera_path;   // gravity frame
  double map_point_size_m = 0.01;  // the map's voxel size
  // The search: every phrase "CLASS" and "CLASS RELATION TARGET" of this map (subject and target
  // canonical, relation on|near|above|under, target a class of the map or floor|table|seat|surface)
  // and the ids `objmap query` returns for it (none listed: nothing matches).
  std::map<std::string, std::vector<int>> queries;
  std::vector<std::string> known_classes;            // COCO-80 and the map's, canonical
  std::map<std::string, std::string> class_aliases;  // other spellings -> canonical
};

struct View3dOptions {
  std::size_t max_map_points = 200000;   // the dense map is thinned to at most this many points
  std::size_t max_object_points = 4000;  // per object
  void check() const;                    // throws objmap::InputError naming the bad field
};

// The map thinned to at most `max_points` (every k-th point, k the smallest that fits).
PointCloud thin_points(const PointCloud& cloud, std::size_t max_points);
// The same of a map of `points` points read from `blocks` (topview.h) once.
PointCloud thin_points(const PointBlocks& blocks, std::size_t points, std::size_t max_points);

// The view's data as JSON, safe inside a <script> element: '<', '>' and '&' written as \u003c,
// \u003e, \u0026 (no "</script>" or "<!--" of a run's names can end it). Points are base64 of
// little-endian uint16 triples on a grid of `step_m` from `origin`.
std::string view3d_json(const View3dContent& content, const View3dOptions& options);

// The section of the page: the canvas, the toolbar (layer toggles, search), the object panel and
// the scripts (three.js, the data, the viewer).
std::string view3d_html(const View3dContent& content, const View3dOptions& options);

// The embedded scripts (generated at build time by scripts/cmake/embed_view3d.cmake).
std::string_view three_js();   // three.js as one expression: `const THREE=(()=>{...})();`
std::string_view view3d_js();  // lib/objmap/report/view3d.js

}  // namespace objmap::report
