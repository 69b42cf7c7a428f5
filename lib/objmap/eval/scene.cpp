#include "objmap/eval/scene.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>

#include "objmap/core/error.h"
#include "objmap/core/format.h"
#include "objmap/core/json_vec.h"
#include "objmap/core/polygon.h"
#include "objmap/eval/json.h"
#include "objmap/eval/objects.h"

namespace objmap::eval {

// ---- frames
// -------------------------------------------------------------------------------------

SceneDescription transform_scene(const SceneDescription& scene, const Similarity& t) {
  SceneDescription out = scene;
  out.up = (t.rotation * scene.up).normalized();
  // A rotation that still takes the new up to +z.
  out.gravity_from_world = scene.gravity_from_world * t.rotation.transpose();
  for (SceneSurface& s : out.surfaces) {
    s.center = t * s.center;
    for (Vec3& corner : s.outline) corner = t * corner;
    s.height_m = t.scale * s.height_m + out.up.dot(t.translation);
    s.area_m2 *= t.scale * t.scale;
  }
  for (io::SceneObject& o : out.objects) {
    o.position = t * o.position;
    if (o.on) o.on->gap_m *= t.scale;
    for (auto* list : {&o.near, &o.above, &o.under})
      for (auto& [id, figure] : *list) figure *= t.scale;
  }
  return out;
}

// ---- the evaluation
// -----------------------------------------------------------------------------

namespace {

bool evaluated_label(const std::string& label) { return label == "floor" || label == "table"; }

// Horizontal distance (across `up`) between two points.
double across(const Vec3& a, const Vec3& b, const Vec3& up) {
  const Vec3 d = a - b;
  return (d - up.dot(d) * up).norm();
}

// One pass of the surface matching: each unmatched true surface (smallest first) takes the unused
// map surface nearest its centre among those whose centre lies inside its outline (and, with
// `same_label`, that carry its label).
void match_surface_pass(const SceneDescription& map, const SceneDescription& gt,
                        const std::vector<std::size_t>& order, bool same_label,
                        std::vector<char>* used, std::vector<SurfaceMatch>* matches) {
  for (const std::size_t i : order) {
    SurfaceMatch& m = (*matches)[i];
    const SceneSurface& g = gt.surfaces[i];
    if (m.map_id) continue;
    std::optional<std::size_t> best;
    for (std::size_t j = 0; j < map.surfaces.size(); ++j) {
      const SceneSurface& s = map.surfaces[j];
      if ((*used)[j] || (same_label && s.label != g.label) ||
          !projects_into_polygon(s.center, g.outline, gt.up))
        continue;
      if (!best ||
          across(s.center, g.center, gt.up) < across(map.surfaces[*best].center, g.center, gt.up))
        best = j;
    }
    if (!best) continue;
    const SceneSurface& s = map.surfaces[*best];
    (*used)[*best] = 1;
    m.map_id = s.id;
    m.map_label = s.label;
    m.map_height_m = s.height_m;
    m.height_error_m = s.height_m - g.height_m;
    m.same_label = s.label == g.label;
  }
}

std::vector<SurfaceMatch> match_surfaces(const SceneDescription& map, const SceneDescription& gt) {
  std::vector<SurfaceMatch> matches;
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < gt.surfaces.size(); ++i) {
    const SceneSurface& g = gt.surfaces[i];
    SurfaceMatch m;
    m.gt_id = g.id;
    m.gt_label = g.label;
    m.gt_height_m = g.height_m;
    matches.push_back(m);
    order.push_back(i);
  }
  // Smaller outlines first: a table or a seat before the floor around it.
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return gt.surfaces[a].area_m2 < gt.surfaces[b].area_m2;
  });
  std::vector<char> used(map.surfaces.size(), 0);
  match_surface_pass(map, gt, order, true, &used, &matches);
  match_surface_pass(map, gt, order, false, &used, &matches);
  return matches;
}

// What the checks of the relations need: the matched ids both ways and the surfaces by id.
struct RelationContext {
  std::map<int, int> map_surface_of_gt;  // true surface id -> map surface id
  std::map<int, int> map_object_of_gt;   // true object id -> map object id
  std::map<int, const SceneSurface*> gt_surfaces, map_surfaces;
};

bool relation_correct(const OnRelation& map_on, const OnRelation& gt_on, const RelationContext& c) {
  const auto lookup = [](const std::map<int, int>& m, int id) {
    const auto it = m.find(id);
    return it == m.end() ? std::optional<int>() : std::optional<int>(it->second);
  };
  if (gt_on.kind == OnRelation::Kind::kObject)
    return map_on.kind == OnRelation::Kind::kObject &&
           lookup(c.map_object_of_gt, gt_on.id) == map_on.id;
  const auto gt_it = c.gt_surfaces.find(gt_on.id);
  const SceneSurface* gt_surface = gt_it == c.gt_surfaces.end() ? nullptr : gt_it->second;
  if (map_on.kind == OnRelation::Kind::kObject)  // a seat: the chair it belongs to
    return gt_surface && gt_surface->object && *gt_surface->object > 0 &&
           lookup(c.map_object_of_gt, *gt_surface->object) == map_on.id;
  if (lookup(c.map_surface_of_gt, gt_on.id) == map_on.id) return true;
  const std::string gt_label = gt_surface ? gt_surface->label : gt_on.label;
  const auto map_it = c.map_surfaces.find(map_on.id);
  const std::string map_label =
      map_it == c.map_surfaces.end() ? map_on.label : map_it->second->label;
  return evaluated_label(gt_label) && map_label == gt_label;
}

std::optional<OnRelation> on_of(const SceneDescription& scene, int object_id) {
  const io::SceneObject* o = scene.object(object_id);
  return o ? o->on : std::nullopt;
}

RelationScores score_relations(const std::vector<RelationCheck>& checks,
                               const std::vector<io::MappedObject>& map_objects,
                               const std::vector<ReferenceObject>& gt_objects,
                               const SceneDescription& map, const SceneDescription& gt,
                               const RelationContext& c) {
  RelationScores r;
  std::set<int> matched_map;
  for (const RelationCheck& check : checks) {
    matched_map.insert(check.map_id);
    r.predicted += check.map_on.has_value();
    r.relevant += check.gt_on.has_value();
    r.correct += check.correct;
  }
  if (r.predicted > 0) r.precision = static_cast<double>(r.correct) / r.predicted;
  if (r.relevant > 0) r.recall = static_cast<double>(r.correct) / r.relevant;
  for (const io::MappedObject& o : map_objects)
    r.unmatched_map_with_on += !matched_map.count(o.id) && on_of(map, o.id).has_value();
  for (const ReferenceObject& o : gt_objects)
    r.unmatched_gt_with_on += !c.map_object_of_gt.count(o.id) && on_of(gt, o.id).has_value();
  return r;
}

}  // namespace

SceneEvalResult evaluate_scene(const std::vector<io::MappedObject>& map_objects,
                               const SceneDescription& map,
                               const std::vector<ReferenceObject>& gt_objects,
                               const SceneDescription& gt, const ObjectEvalOptions& options) {
  SceneEvalResult result;
  // 1. The up direction.
  result.up_angle_deg = std::acos(std::clamp(map.up.dot(gt.up), -1.0, 1.0)) * 180.0 / M_PI;

  // 2. The surfaces.
  result.surfaces = match_surfaces(map, gt);
  std::vector<double> height_errors;
  RelationContext context;
  for (const SurfaceMatch& m : result.surfaces) {
    if (m.map_id) context.map_surface_of_gt[m.gt_id] = *m.map_id;
    if (!evaluated_label(m.gt_label)) continue;
    if (m.map_id) height_errors.push_back(std::abs(m.height_error_m));
    ++(m.map_id ? result.found : result.missed);
  }
  result.height_abs_error_m = compute_stats(height_errors);

  // 3. The `on` relations of the object pairs that eval objects matches.
  for (const SceneSurface& s : gt.surfaces) context.gt_surfaces[s.id] = &s;
  for (const SceneSurface& s : map.surfaces) context.map_surfaces[s.id] = &s;
  const ObjectEvalResult objects = evaluate_objects(map_objects, gt_objects, options);
  for (const ObjectMatch& m : objects.matches) context.map_object_of_gt[m.reference_id] = m.map_id;
  for (const ObjectMatch& m : objects.matches) {
    RelationCheck check;
    check.gt_id = m.reference_id;
    check.map_id = m.map_id;
    check.class_name = m.class_name;
    check.gt_on = on_of(gt, m.reference_id);
    check.map_on = on_of(map, m.map_id);
    check.correct =
        check.gt_on && check.map_on && relation_correct(*check.map_on, *check.gt_on, context);
    result.relations.push_back(check);
  }
  result.on = score_relations(result.relations, map_objects, gt_objects, map, gt, context);
  return result;
}

// ---- output
// -------------------------------------------------------------------------------------

namespace {

using nlohmann::ordered_json;

ordered_json relation_json(const std::optional<OnRelation>& on) {
  if (!on) return nullptr;
  ordered_json j;
  j["kind"] = on->kind == OnRelation::Kind::kSurface ? "surface" : "object";
  j["id"] = on->id;
  j["label"] = on->label;
  return j;
}

ordered_json alignment_json(const SceneAlignment& a) {
  ordered_json j;
  j["gt_trajectory"] = a.gt_trajectory;
  j["trajectory"] = a.trajectory;
  ordered_json rotation = ordered_json::array();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) rotation.push_back(a.gt_from_map.rotation(r, c));
  j["gt_from_map"] = {{"rotation", rotation},
                      {"translation", vec3_json(a.gt_from_map.translation)}};
  j["ate_m"] = stats_json(a.ate_m);
  return j;
}

ordered_json surfaces_json(const SceneEvalResult& r) {
  ordered_json matches = ordered_json::array();
  for (const SurfaceMatch& m : r.surfaces) {
    ordered_json j;
    j["gt_id"] = m.gt_id;
    j["gt_label"] = m.gt_label;
    j["gt_height_m"] = m.gt_height_m;
    j["map_id"] = m.map_id ? ordered_json(*m.map_id) : ordered_json(nullptr);
    j["map_label"] = m.map_id ? ordered_json(m.map_label) : ordered_json(nullptr);
    j["map_height_m"] = m.map_id ? ordered_json(m.map_height_m) : ordered_json(nullptr);
    j["height_error_m"] = m.map_id ? ordered_json(m.height_error_m) : ordered_json(nullptr);
    j["same_label"] = m.same_label;
    matches.push_back(j);
  }
  ordered_json j;
  j["found"] = r.found;
  j["missed"] = r.missed;
  j["height_abs_error_m"] = stats_json(r.height_abs_error_m);
  j["matches"] = matches;
  return j;
}

ordered_json relations_json(const SceneEvalResult& r) {
  ordered_json pairs = ordered_json::array();
  for (const RelationCheck& c : r.relations) {
    ordered_json j;
    j["gt_id"] = c.gt_id;
    j["map_id"] = c.map_id;
    j["class"] = c.class_name;
    j["gt_on"] = relation_json(c.gt_on);
    j["map_on"] = relation_json(c.map_on);
    j["correct"] = c.correct;
    pairs.push_back(j);
  }
  ordered_json j;
  j["precision"] = r.on.precision;
  j["recall"] = r.on.recall;
  j["predicted"] = r.on.predicted;
  j["relevant"] = r.on.relevant;
  j["correct"] = r.on.correct;
  j["unmatched_map_with_on"] = r.on.unmatched_map_with_on;
  j["unmatched_gt_with_on"] = r.on.unmatched_gt_with_on;
  j["pairs"] = pairs;
  return j;
}

}  // namespace

std::string scene_eval_json(const SceneEvalReport& report) {
  ordered_json out;
  out["map"] = report.map_source;
  out["gt"] = report.gt_source;
  out["gate_m"] = report.options.gate_m;
  out["alignment"] = report.alignment ? alignment_json(*report.alignment) : ordered_json(nullptr);
  out["up_angle_deg"] = report.result.up_angle_deg;
  out["surfaces"] = surfaces_json(report.result);
  out["on"] = relations_json(report.result);
  return out.dump(2) + "\n";
}

std::string scene_eval_text(const SceneEvalReport& report) {
  const SceneEvalResult& r = report.result;
  std::string out = "Scene  " + report.map_source + "  vs  " + report.gt_source + "\n";
  if (report.alignment)
    out += "  frame     aligned by " + report.alignment->trajectory + " onto " +
           report.alignment->gt_trajectory + " (ATE rmse " +
           fixed_text(report.alignment->ate_m.rmse, 4) + " m)\n";
  out += "  up        angle error " + fixed_text(r.up_angle_deg, 3) + " deg\n";
  out += "  surfaces  floor and table found " + std::to_string(r.found) + " of " +
         std::to_string(r.found + r.missed) + ", |height error| max " +
         fixed_text(r.height_abs_error_m.max, 4) + " m\n";
  for (const SurfaceMatch& m : r.surfaces) {
    out += "    true " + std::to_string(m.gt_id) + " " + m.gt_label + " at " +
           fixed_text(m.gt_height_m, 3) + " m: ";
    out += m.map_id ? "map " + std::to_string(*m.map_id) + " " + m.map_label + " at " +
                          fixed_text(m.map_height_m, 3) + " m, error " +
                          fixed_text(m.height_error_m, 4) + " m\n"
                    : std::string("missed\n");
  }
  out += "  on        precision " + fixed_text(r.on.precision, 3) + " (" +
         std::to_string(r.on.correct) + "/" + std::to_string(r.on.predicted) + "), recall " +
         fixed_text(r.on.recall, 3) + " (" + std::to_string(r.on.correct) + "/" +
         std::to_string(r.on.relevant) + ") over " + std::to_string(r.relations.size()) +
         " matched objects\n";
  return out;
}

}  // namespace objmap::eval
