#include "objmap/pipeline/fuse_scene.h"

#include <chrono>

#include "objmap/core/clock.h"
#include "objmap/core/json_vec.h"
#include "objmap/geometry/bounds.h"

namespace objmap::pipeline {
namespace {

using nlohmann::ordered_json;

ordered_json rows(const Eigen::Matrix3d& m) {
  ordered_json a = ordered_json::array();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) a.push_back(m(i, j));
  return a;
}

std::vector<scene::SceneObject> scene_objects(const std::vector<fusion::ObjectRecord>& records) {
  std::vector<scene::SceneObject> objects;
  for (const auto& r : records) objects.push_back({r.id, r.class_name, r.position, &r.cloud});
  return objects;
}

ordered_json neighbours_json(const std::vector<scene::Neighbour>& list, const char* key) {
  ordered_json a = ordered_json::array();
  for (const auto& n : list) a.push_back({{"id", n.id}, {key, n.distance_m}});
  return a;
}

ordered_json relations_json(const scene::Relations& r) {
  ordered_json o;
  if (r.on)
    o["on"] = {
        {"kind", r.on->kind}, {"id", r.on->id}, {"label", r.on->label}, {"gap_m", r.on->gap_m}};
  else
    o["on"] = nullptr;
  o["near"] = neighbours_json(r.near, "distance_m");
  o["near_surfaces"] = neighbours_json(r.near_surfaces, "distance_m");
  o["above"] = neighbours_json(r.above, "gap_m");
  o["under"] = neighbours_json(r.under, "gap_m");
  ordered_json duplicates = ordered_json::array();
  for (const auto& d : r.duplicates) duplicates.push_back({{"id", d.id}, {"overlap", d.overlap}});
  o["suspected_duplicates"] = duplicates;
  return o;
}

ordered_json surface_json(const scene::Surface& s) {
  ordered_json o;
  o["id"] = s.id;
  o["label"] = s.label;
  o["height_m"] = s.height_m;
  o["center"] = vec3_json(s.center);
  o["area_m2"] = s.area_m2;
  ordered_json outline = ordered_json::array();
  for (const Vec3& p : s.outline) outline.push_back(vec3_json(p));
  o["outline"] = outline;
  o["points"] = s.points;
  if (s.object) o["object"] = *s.object;
  o["rule"] = s.label_rule;
  return o;
}

}  // namespace

void relate_to_scene(std::vector<fusion::ObjectRecord>& records, const scene::SceneOptions& options,
                     const fusion::RecordOptions& record_options, scene::SceneGraph& graph) {
  const auto t0 = Clock::now();
  std::vector<geometry::SupportPlane> planes;
  for (const scene::Surface& s : graph.surfaces) planes.push_back({s.height_m, s.area_m2});
  for (auto& r : records) {
    if (record_options.position_is_centroid) {
      r.obb = geometry::compute_upright_obb(r.cloud, graph.up.up);
      continue;
    }
    std::vector<bool> strip;
    if (record_options.position_without_support)
      strip = geometry::support_strip(r.cloud, graph.up.gravity_from_world, planes,
                                      record_options.support_strip);
    r.points_support = static_cast<std::size_t>(std::count(strip.begin(), strip.end(), true));
    const PointCloud& body = r.points_support ? geometry::without(r.cloud, strip) : r.cloud;
    r.position = geometry::percentile_box_centre(body, record_options.position_percentile,
                                                 graph.up.gravity_from_world);
    r.obb = geometry::compute_upright_obb(body, graph.up.up);
  }
  const std::vector<scene::SceneObject> objects = scene_objects(records);
  scene::mark_object_tops(graph.surfaces, graph.up.up, objects);
  graph.relations = scene::relate_objects(objects, graph.surfaces, graph.up.up, options.surfaces,
                                          options.relations);
  graph.seconds_relations = seconds_since(t0);
}

void add_scene_json(const scene::SceneGraph& graph, ordered_json& doc) {
  doc["up_in_world"] = vec3_json(graph.up.up);
  doc["gravity_from_world"] = rows(graph.up.gravity_from_world);
  ordered_json surfaces = ordered_json::array();
  for (const auto& s : graph.surfaces) surfaces.push_back(surface_json(s));
  doc["surfaces"] = surfaces;
  auto& objects = doc["objects"];
  for (std::size_t i = 0; i < objects.size() && i < graph.relations.size(); ++i)
    objects[i]["relations"] = relations_json(graph.relations[i]);
}

ordered_json scene_run_json(const scene::SceneGraph& graph) {
  const scene::UpEstimate& u = graph.up;
  ordered_json planes = ordered_json::array();
  for (const auto& p : u.planes)
    planes.push_back({{"normal", vec3_json(p.normal)},
                      {"offset_m", p.offset},
                      {"inliers", p.inliers},
                      {"angle_to_prior_deg", p.angle_to_prior_deg},
                      {"view_elevation", p.view_elevation},
                      {"used", p.used}});
  ordered_json up = {{"source", u.source},
                     {"up_in_world", vec3_json(u.up)},
                     {"camera_prior", vec3_json(u.camera_prior)},
                     {"camera_view", vec3_json(u.camera_view)},
                     {"camera_agreement", u.camera_agreement},
                     {"prior_to_up_deg", u.prior_to_up_deg},
                     {"sample_points", u.sample_points},
                     {"planes", planes},
                     {"warnings", u.warnings}};
  ordered_json labels = ordered_json::object();
  for (const auto& s : graph.surfaces) labels[s.label] = labels.value(s.label, 0) + 1;
  std::size_t on = 0;
  for (const auto& r : graph.relations) on += r.on ? 1 : 0;
  return {{"up", up},
          {"surfaces", graph.surfaces.size()},
          {"surface_labels", labels},
          {"objects_on_something", on}};
}

}  // namespace objmap::pipeline
