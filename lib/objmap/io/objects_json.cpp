#include "objmap/io/objects_json.h"

#include "objmap/io/json_file.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <system_error>

#include "objmap/core/error.h"
#include "objmap/io/run_path.h"

namespace objmap::io {

namespace {

using nlohmann::json;

constexpr double kIntMin = std::numeric_limits<int>::min();
constexpr double kIntMax = std::numeric_limits<int>::max();
constexpr double kMaxCount = 9007199254740992.0;  // 2^53: every whole double up to it is exact

const json& field(const json& j, const std::string& key, const std::string& where) {
  if (!j.is_object() || !j.contains(key))
    throw InputError(where, "missing field '" + key + "'; expected an objmap objects.json");
  return j[key];
}

double number(const json& j, const std::string& key, const std::string& where) {
  const json& v = field(j, key, where);
  if (!v.is_number()) throw InputError(where + "." + key, "expected a number, got " + v.dump());
  return v.get<double>();
}

// A whole number in [low, high]; checked before any cast (a double outside an integer type's range,
// 1e300 or -1 for a count, has no value of that type).
double whole_number(const json& j, const std::string& key, const std::string& where, double low,
                    double high) {
  const double v = number(j, key, where);
  if (!(v >= low && v <= high) || v != std::floor(v))
    throw InputError(where + "." + key, "expected a whole number in [" +
                                            std::to_string(static_cast<long long>(low)) + ", " +
                                            std::to_string(static_cast<long long>(high)) +
                                            "], got " + field(j, key, where).dump());
  return v;
}

Vec3 vec3(const json& j, const std::string& key, const std::string& where) {
  const json& v = field(j, key, where);
  if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
    throw InputError(where + "." + key, "expected [x, y, z], got " + v.dump());
  return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
}

}  // namespace

std::vector<MappedObject> read_objects_json(const std::filesystem::path& file) {
  // A folder opens as a stream on Linux; reading it then throws std::ios_base::failure.
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec))
    throw InputError(file.string(), "is a folder; expected RUN/objects.json of objmap fuse");
  const json doc = read_json_file(file, "cannot open; expected RUN/objects.json of objmap fuse");
  const json& objects = field(doc, "objects", file.string());
  if (!objects.is_array()) throw InputError(file.string() + ": objects", "expected an array");
  std::vector<MappedObject> out;
  std::set<int> ids;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const json& o = objects[i];
    const std::string where = file.string() + ": objects[" + std::to_string(i) + "]";
    MappedObject m;
    m.id = static_cast<int>(whole_number(o, "id", where, kIntMin, kIntMax));
    if (!ids.insert(m.id).second)
      throw InputError(where + ".id",
                       "id " + std::to_string(m.id) + " appears twice; expected unique ids");
    const json& cls = field(o, "class", where);
    if (!cls.is_string()) throw InputError(where + ".class", "expected a string");
    m.class_name = cls.get<std::string>();
    m.score = number(o, "score", where);
    m.centroid = vec3(o, "centroid", where);
    m.position = o.contains("position") ? vec3(o, "position", where) : m.centroid;
    const json& aabb = field(o, "aabb", where);
    m.aabb.min = vec3(aabb, "min", where + ".aabb");
    m.aabb.max = vec3(aabb, "max", where + ".aabb");
    const json& obb = field(o, "obb", where);
    m.obb.center = vec3(obb, "center", where + ".obb");
    m.obb.half_extent = vec3(obb, "half_extent", where + ".obb");
    if (!(m.obb.half_extent.minCoeff() >= 0))
      throw InputError(where + ".obb.half_extent", "negative half extent; expected >= 0");
    const json& rot = field(obb, "rotation", where + ".obb");
    if (!rot.is_array() || rot.size() != 9 ||
        !std::all_of(rot.begin(), rot.end(), [](const json& v) { return v.is_number(); }))
      throw InputError(where + ".obb.rotation", "expected 9 numbers (row-major)");
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) m.obb.rotation(r, c) = rot[3 * r + c].get<double>();
    m.points = static_cast<std::size_t>(whole_number(field(o, "points", where), "outlier_filtered",
                                                     where + ".points", 0, kMaxCount));
    m.observations = static_cast<int>(whole_number(o, "observation_count", where, 0, kIntMax));
    const json& ply = field(o, "ply", where);
    if (ply.is_string()) m.ply = ply.get<std::string>();
    if (!m.ply.empty())  // a file of the run: it must stay inside the run folder
      path_in_run(file.parent_path(), m.ply, file, "objects[" + std::to_string(i) + "].ply");
    out.push_back(std::move(m));
  }
  return out;
}

std::vector<Sighting> read_sightings(const std::filesystem::path& file) {
  const json doc = read_json_file(file, "cannot open; expected RUN/objects.json of objmap fuse");
  if (!doc.is_object() || !doc.contains("sightings")) return {};
  const json& list = doc["sightings"];
  if (!list.is_array()) throw InputError(file.string() + ": sightings", "expected an array");
  std::vector<Sighting> out;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const json& o = list[i];
    const std::string where = file.string() + ": sightings[" + std::to_string(i) + "]";
    Sighting s;
    s.id = static_cast<int>(whole_number(o, "id", where, kIntMin, kIntMax));
    const json& cls = field(o, "class", where);
    if (!cls.is_string()) throw InputError(where + ".class", "expected a string");
    s.class_name = cls.get<std::string>();
    s.score = number(o, "score", where);
    s.position = vec3(o, "position", where);
    s.first_seen = number(o, "first_seen", where);
    s.last_seen = number(o, "last_seen", where);
    s.frames = static_cast<int>(whole_number(o, "frames", where, 0, kIntMax));
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace objmap::io
