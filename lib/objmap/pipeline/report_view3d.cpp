#include "objmap/pipeline/report_view3d.h"

#include <set>

#include "objmap/core/format.h"
#include "objmap/fusion/palette.h"
#include "objmap/report/scene_graph.h"
#include "objmap/scene/query.h"
#include "objmap/segmentation/coco_classes.h"

namespace objmap::pipeline {
namespace {

// "5 (keyboard)" for an object of the scene, "5" for one it does not know.
std::string object_text(const io::SceneDescription& scene, int id) {
  const io::SceneObject* o = scene.object(id);
  return std::to_string(id) + (o ? " (" + o->class_name + ")" : "");
}

// One line per relation of objects.json: "on surface 2 (table), gap 0.004 m", "near 5 (keyboard),
// 0.210 m", "above 3 (book), 0.120 m", "under ...".
std::vector<std::string> relation_lines(const io::SceneDescription& scene, int id) {
  const io::SceneObject* o = scene.object(id);
  if (!o) return {};
  std::vector<std::string> lines;
  if (o->on) {
    const bool surface = o->on->kind == io::SceneRelation::Kind::kSurface;
    lines.push_back(std::string("on ") + (surface ? "surface " : "object ") +
                    std::to_string(o->on->id) + " (" + o->on->label + "), gap " +
                    fixed_text(o->on->gap_m, 3) + " m");
  }
  const std::pair<const char*, const std::vector<std::pair<int, double>>*> lists[] = {
      {"near", &o->near}, {"above", &o->above}, {"under", &o->under}};
  for (const auto& [name, list] : lists)
    for (const auto& [other, d] : *list)
      lines.push_back(std::string(name) + " " + object_text(scene, other) + ", " +
                      fixed_text(d, 3) + " m");
  if (o->near_surfaces)
    for (const auto& [id, d] : *o->near_surfaces) {
      const io::SceneSurface* s = scene.surface(id);
      lines.push_back("near surface " + std::to_string(id) + (s ? " (" + s->label + ")" : "") +
                      ", " + fixed_text(d, 3) + " m");
    }
  return lines;
}

std::vector<report::View3dSurface> view3d_surfaces(const io::SceneDescription& scene,
                                                   const Eigen::Matrix3d& gravity) {
  const std::optional<double> floor = report::floor_height_m(scene);
  std::vector<report::View3dSurface> out;
  for (const io::SceneSurface& s : scene.surfaces) {
    report::View3dSurface v;
    v.id = s.id;
    v.label = s.label;
    if (floor) v.above_floor_m = s.height_m - *floor;
    for (const Vec3& p : s.outline) v.outline.push_back(gravity * p);
    out.push_back(std::move(v));
  }
  return out;
}

}  // namespace

std::map<std::string, std::vector<int>> all_query_matches(const io::SceneDescription& scene) {
  std::set<std::string> classes;
  for (const io::SceneObject& o : scene.objects)
    classes.insert(segmentation::canonical_class(o.class_name));
  std::vector<std::string> targets(classes.begin(), classes.end());
  for (const char* s : {"floor", "table", "seat", "surface"}) targets.push_back(s);
  std::vector<std::string> phrases(classes.begin(), classes.end());
  for (const std::string& subject : classes)
    for (const char* relation : {"on", "near", "above", "under"})
      for (const std::string& target : targets)
        phrases.push_back(subject + " " + relation + " " + target);
  std::map<std::string, std::vector<int>> out;
  for (const std::string& phrase : phrases) {
    const scene::Query q = scene::parse_query(phrase, scene);
    const std::string key =
        q.relation.empty() ? q.subject : q.subject + " " + q.relation + " " + q.target;
    std::vector<int> ids;
    for (const scene::QueryMatch& m : scene::run_query(q, scene).matches)
      ids.push_back(m.object->id);
    if (!ids.empty()) out[key] = ids;
  }
  return out;
}

report::View3dContent view3d_content(View3dInputs in) {
  const Eigen::Matrix3d g = in.gravity_from_world.value_or(Eigen::Matrix3d::Identity());
  const Eigen::Matrix3f gf = g.cast<float>();
  report::View3dContent c;
  c.map = std::move(in.map);
  c.map_points_total = in.map_points_total;
  c.map_point_size_m = in.map_point_size_m;
  for (std::size_t i = 0; i < in.objects->size(); ++i) {
    const io::MappedObject& o = (*in.objects)[i];
    report::View3dObject v;
    v.id = o.id;
    v.class_name = o.class_name;
    v.color = fusion::class_color(o.class_name);
    v.obb = o.obb;
    v.obb.center = g * o.obb.center;
    v.obb.rotation = g * o.obb.rotation;
    v.observations = o.observations;
    v.views = i < in.views.size() ? in.views[i] : 0;
    v.score = o.score;
    if (i < in.clouds.size())
      for (const Vec3f& p : in.clouds[i].points) v.points.push_back(gf * p);
    if (i < in.meshes.size() && !in.meshes[i].empty()) {
      for (const Vec3f& p : in.meshes[i].vertices) v.mesh_vertices.push_back(gf * p);
      for (const auto& t : in.meshes[i].triangles)
        for (const std::uint32_t k : t) v.mesh_triangles.push_back(static_cast<int>(k));
    }
    if (in.scene) v.relations = relation_lines(*in.scene, o.id);
    c.objects.push_back(std::move(v));
  }
  for (const Vec3& p : in.camera_path) c.camera_path.push_back(g * p);
  c.known_classes = segmentation::coco80_names();
  for (const io::MappedObject& o : *in.objects)
    c.known_classes.push_back(segmentation::canonical_class(o.class_name));
  c.class_aliases = segmentation::class_aliases();
  if (in.scene) {
    c.surfaces = view3d_surfaces(*in.scene, g);
    c.queries = all_query_matches(*in.scene);
  } else {  // no relations to ask about: a class alone still finds its objects
    for (const io::MappedObject& o : *in.objects)
      c.queries[segmentation::canonical_class(o.class_name)].push_back(o.id);
  }
  return c;
}

}  // namespace objmap::pipeline
