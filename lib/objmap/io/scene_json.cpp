#include "objmap/io/scene_json.h"

#include <nlohmann/json.hpp>
#include <set>
#include <system_error>

#include "objmap/core/error.h"
#include "objmap/io/json_file.h"

namespace objmap::io {

namespace {

using nlohmann::json;

// Which file is read and how: the messages say what was expected.
struct SceneFile {
  std::string path;
  std::string expected;  // "objects.json of an objmap fuse that estimates the scene ..."
  bool map = false;      // objects.json (relations, position, gravity); else objects_gt.json
};

const json& need(const json& j, const std::string& key, const std::string& where,
                 const SceneFile& file) {
  if (!j.is_object() || !j.contains(key))
    throw InputError(where, "missing field '" + key + "'; expected " + file.expected);
  return j[key];
}

Vec3 read_vec3(const json& v, const std::string& where) {
  if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
    throw InputError(where, "expected [x, y, z], got " + v.dump());
  return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
}

double read_number(const json& v, const std::string& where) {
  if (!v.is_number()) throw InputError(where, "expected a number, got " + v.dump());
  return v.get<double>();
}

int read_id(const json& v, const std::string& where) {
  if (!v.is_number_integer()) throw InputError(where, "expected an integer id, got " + v.dump());
  return v.get<int>();
}

std::string read_string(const json& v, const std::string& where) {
  if (!v.is_string()) throw InputError(where, "expected a string, got " + v.dump());
  return v.get<std::string>();
}

std::string read_label(const json& j, const std::string& where) {
  return j.contains("label") ? read_string(j["label"], where + ".label") : "";
}

// `key_where` names the field itself in the message of a field that is no array.
const json& need_array(const json& j, const std::string& key, const std::string& where,
                       const std::string& key_where, const SceneFile& file) {
  const json& a = need(j, key, where, file);
  if (!a.is_array()) throw InputError(key_where, "expected an array, got " + a.dump());
  return a;
}

Vec3 read_up(const json& doc, const SceneFile& file) {
  const Vec3 up = read_vec3(need(doc, "up_in_world", file.path, file), file.path + ": up_in_world");
  if (!(up.norm() > 1e-9) || !up.allFinite())
    throw InputError(file.path + ": up_in_world", "is a zero vector; expected a unit vector");
  return up.normalized();
}

Eigen::Matrix3d read_gravity(const json& doc, const SceneFile& file) {
  const json& g = need(doc, "gravity_from_world", file.path, file);
  const std::string where = file.path + ": gravity_from_world";
  if (!g.is_array() || g.size() != 9) throw InputError(where, "expected 9 numbers (row-major)");
  Eigen::Matrix3d m;
  for (int i = 0; i < 9; ++i)
    m(i / 3, i % 3) = read_number(g[i], where + "[" + std::to_string(i) + "]");
  return m;
}

SceneSurface read_surface(const json& s, const std::string& where, const SceneFile& file) {
  SceneSurface out;
  out.id = read_id(need(s, "id", where, file), where + ".id");
  out.label = read_label(s, where);
  out.height_m = read_number(need(s, "height_m", where, file), where + ".height_m");
  out.center = read_vec3(need(s, "center", where, file), where + ".center");
  if (s.contains("outline")) {
    const json& outline = s["outline"];
    if (!outline.is_array()) throw InputError(where + ".outline", "expected an array of [x, y, z]");
    for (std::size_t k = 0; k < outline.size(); ++k)
      out.outline.push_back(read_vec3(outline[k], where + ".outline[" + std::to_string(k) + "]"));
  }
  if (s.contains("area_m2")) out.area_m2 = read_number(s["area_m2"], where + ".area_m2");
  if (s.contains("object")) out.object = read_id(s["object"], where + ".object");
  return out;
}

std::optional<SceneRelation> read_on(const json& on, const std::string& where,
                                     const SceneFile& file) {
  if (on.is_null()) return std::nullopt;
  const json& kind = need(on, "kind", where, file);
  SceneRelation r;
  if (kind == "surface")
    r.kind = SceneRelation::Kind::kSurface;
  else if (kind == "object")
    r.kind = SceneRelation::Kind::kObject;
  else
    throw InputError(where + ".kind", "is " + kind.dump() + "; expected \"surface\" or \"object\"");
  r.id = read_id(need(on, "id", where, file), where + ".id");
  r.label = read_label(on, where);
  if (file.map) r.gap_m = read_number(need(on, "gap_m", where, file), where + ".gap_m");
  return r;
}

// relations.near / above / under: [{"id": .., `figure`: ..}, ...].
std::vector<std::pair<int, double>> read_neighbours(const json& relations, const std::string& key,
                                                    const char* figure, const std::string& where,
                                                    const SceneFile& file) {
  const json& list = need_array(relations, key, where, where + "." + key, file);
  std::vector<std::pair<int, double>> out;
  for (std::size_t k = 0; k < list.size(); ++k) {
    const std::string at = where + "." + key + "[" + std::to_string(k) + "]";
    out.emplace_back(read_id(need(list[k], "id", at, file), at + ".id"),
                     read_number(need(list[k], figure, at, file), at + "." + figure));
  }
  return out;
}

SceneObject read_object(const json& o, const std::string& where, const SceneFile& file) {
  SceneObject out;
  out.id = read_id(need(o, "id", where, file), where + ".id");
  if (!file.map) {  // objects_gt.json: objects[].on
    if (o.contains("class")) out.class_name = read_string(o["class"], where + ".class");
    out.on = read_on(need(o, "on", where, file), where + ".on", file);
    return out;
  }
  out.class_name = read_string(need(o, "class", where, file), where + ".class");
  out.position = read_vec3(need(o, "position", where, file), where + ".position");
  const json& relations = need(o, "relations", where, file);
  const std::string at = where + ".relations";
  out.on = read_on(need(relations, "on", at, file), at + ".on", file);
  out.near = read_neighbours(relations, "near", "distance_m", at, file);
  out.above = read_neighbours(relations, "above", "gap_m", at, file);
  out.under = read_neighbours(relations, "under", "gap_m", at, file);
  if (relations.contains("near_surfaces"))
    out.near_surfaces = read_neighbours(relations, "near_surfaces", "distance_m", at, file);
  return out;
}

json parse_file(const SceneFile& file) {
  std::error_code ec;
  if (std::filesystem::is_directory(file.path, ec))
    throw InputError(file.path, "is a folder; expected " + file.expected);
  return read_json_file(file.path, "cannot open; expected " + file.expected);
}

SceneDescription read_scene(const SceneFile& file) {
  const json doc = parse_file(file);
  SceneDescription scene;
  scene.source = file.path;
  scene.up = read_up(doc, file);
  if (file.map) scene.gravity_from_world = read_gravity(doc, file);
  const json& surfaces = need_array(doc, "surfaces", file.path, file.path + ": surfaces", file);
  std::set<int> ids;
  for (std::size_t i = 0; i < surfaces.size(); ++i) {
    const std::string where = file.path + ": surfaces[" + std::to_string(i) + "]";
    scene.surfaces.push_back(read_surface(surfaces[i], where, file));
    if (!ids.insert(scene.surfaces.back().id).second)
      throw InputError(where + ".id", "appears twice; expected unique surface ids");
  }
  const json& objects = need_array(doc, "objects", file.path, file.path + ": objects", file);
  ids.clear();
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const std::string where = file.path + ": objects[" + std::to_string(i) + "]";
    scene.objects.push_back(read_object(objects[i], where, file));
    if (!ids.insert(scene.objects.back().id).second)
      throw InputError(where + ".id", "appears twice; expected unique object ids");
  }
  return scene;
}

}  // namespace

const SceneObject* SceneDescription::object(int id) const {
  for (const auto& o : objects)
    if (o.id == id) return &o;
  return nullptr;
}

const SceneSurface* SceneDescription::surface(int id) const {
  for (const auto& s : surfaces)
    if (s.id == id) return &s;
  return nullptr;
}

SceneDescription read_map_scene(const std::filesystem::path& objects_json) {
  return read_scene({objects_json.string(),
                     "objects.json of an objmap fuse that estimates the scene (up_in_world, "
                     "gravity_from_world, surfaces, objects[].relations; "
                     "schemas/objects.schema.json)",
                     true});
}

SceneDescription read_gt_scene(const std::filesystem::path& objects_gt_json) {
  return read_scene({objects_gt_json.string(),
                     "objects_gt.json of objmap synth with up_in_world, surfaces and objects[].on "
                     "(schemas/objects_gt.schema.json)",
                     false});
}

}  // namespace objmap::io
