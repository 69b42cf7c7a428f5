// The ground-truth objects of the object evaluation: objects_gt.json and the cuboid files.
#include "objmap/eval/objects.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <tuple>

#include "objmap/core/error.h"
#include "objmap/core/format.h"
#include "objmap/core/json_vec.h"
#include "objmap/eval/json.h"
#include "objmap/io/json_file.h"
#include "objmap/io/text_lines.h"
#include "objmap/segmentation/coco_classes.h"
#include "objmap/track/assignment.h"

namespace objmap::eval {

// ---- ground-truth objects
// -----------------------------------------------------------------------

namespace {

using nlohmann::json;

const char* const kCannotOpenGt =
    "cannot open; expected objects_gt.json (objmap synth) or a cuboid list "
    "\"x y z yaw half_x half_y half_z\"";

const json& gt_field(const json& j, const std::string& key, const std::string& where) {
  if (!j.is_object() || !j.contains(key))
    throw InputError(where, "missing field '" + key +
                                "'; expected objects_gt.json (schemas/objects_gt.schema.json)");
  return j[key];
}

std::vector<double> gt_numbers(const json& j, const std::string& key, std::size_t n,
                               const std::string& where) {
  const json& v = gt_field(j, key, where);
  bool ok = v.is_array() && v.size() == n;
  for (std::size_t i = 0; ok && i < n; ++i) ok = v[i].is_number();
  if (!ok)
    throw InputError(where + "." + key,
                     "expected an array of " + std::to_string(n) + " numbers, got " + v.dump());
  std::vector<double> out;
  for (std::size_t i = 0; i < n; ++i) out.push_back(v[i].get<double>());
  return out;
}

std::vector<ReferenceObject> read_objects_gt_json(const std::filesystem::path& file) {
  const json doc = io::read_json_file(file, kCannotOpenGt);
  const json& objects = gt_field(doc, "objects", file.string());
  if (!objects.is_array()) throw InputError(file.string() + ": objects", "expected an array");
  std::vector<ReferenceObject> out;
  std::set<int> ids;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const json& o = objects[i];
    const std::string where = file.string() + ": objects[" + std::to_string(i) + "]";
    ReferenceObject r;
    const json& id = gt_field(o, "id", where);
    if (!id.is_number_integer())
      throw InputError(where + ".id", "expected an integer, got " + id.dump());
    r.id = id.get<int>();
    if (!ids.insert(r.id).second)
      throw InputError(where + ".id",
                       "id " + std::to_string(r.id) + " appears twice; expected unique ids");
    const json& cls = gt_field(o, "class", where);
    if (!cls.is_string() || cls.get<std::string>().empty())
      throw InputError(where + ".class", "expected a non-empty string, got " + cls.dump());
    r.class_name = cls.get<std::string>();
    const auto c = gt_numbers(o, "centroid", 3, where);
    r.centroid = {c[0], c[1], c[2]};
    const json& obb = gt_field(o, "obb", where);
    const auto center = gt_numbers(obb, "center", 3, where + ".obb");
    const auto rotation = gt_numbers(obb, "rotation", 9, where + ".obb");
    const auto half = gt_numbers(obb, "half_extent", 3, where + ".obb");
    r.obb.center = {center[0], center[1], center[2]};
    for (int row = 0; row < 3; ++row)
      for (int col = 0; col < 3; ++col) r.obb.rotation(row, col) = rotation[3 * row + col];
    r.obb.half_extent = {half[0], half[1], half[2]};
    if (r.obb.half_extent.minCoeff() < 0)
      throw InputError(where + ".obb.half_extent", "negative half extent; expected >= 0");
    r.position = r.obb.center;
    out.push_back(std::move(r));
  }
  return out;
}

std::vector<ReferenceObject> read_objects_gt_cuboids(const std::filesystem::path& file,
                                                     const std::string& default_class) {
  io::LineReader in(file);
  std::vector<ReferenceObject> out;
  while (in.next()) {
    // A position list ("id class x y z [key value]...", e.g. ycbv_0000_10f/objects_gt.txt): the
    // second field is a class name, not a number. Such an object has a position and no extent.
    char* end = nullptr;
    const std::string& second = in.field(in.fields().size() > 1 ? 1 : 0);
    std::strtod(second.c_str(), &end);
    if (in.fields().size() >= 5 && *end != '\0') {  // not wholly a number ("009_gelatin_box")
      ReferenceObject r;
      const std::int64_t id = in.integer(0, "id");
      if (id < std::numeric_limits<int>::min() || id > std::numeric_limits<int>::max())
        throw InputError(in.where(), "id " + std::to_string(id) + "; expected an int");
      r.id = static_cast<int>(id);
      r.class_name = second;  // '_' for spaces, as objmap names classes ("009 gelatin box")
      std::replace(r.class_name.begin(), r.class_name.end(), '_', ' ');
      r.centroid = {in.number(2, "x"), in.number(3, "y"), in.number(4, "z")};
      r.obb.center = r.centroid;
      r.obb.rotation = Eigen::Matrix3d::Identity();
      r.obb.half_extent = Vec3::Zero();
      r.position = r.centroid;
      out.push_back(std::move(r));
      continue;
    }
    in.expect_fields(7, "x y z yaw half_x half_y half_z (metres, radians)");
    ReferenceObject r;
    r.id = static_cast<int>(out.size()) + 1;
    r.class_name = default_class;
    r.obb.center = {in.number(0, "x"), in.number(1, "y"), in.number(2, "z")};
    const double yaw = in.number(3, "yaw");
    r.obb.rotation = Eigen::AngleAxisd(yaw, Vec3::UnitZ()).toRotationMatrix();
    r.obb.half_extent = {in.number(4, "half_x"), in.number(5, "half_y"), in.number(6, "half_z")};
    if (r.obb.half_extent.minCoeff() < 0)
      throw InputError(in.where(), "negative half extent; expected half sizes >= 0");
    r.centroid = r.position = r.obb.center;
    out.push_back(std::move(r));
  }
  if (out.empty())
    throw InputError(file.string(),
                     "no cuboid; expected lines \"x y z yaw half_x half_y half_z\", "
                     "\"id class x y z\" or objects_gt.json");
  return out;
}

}  // namespace

std::vector<ReferenceObject> read_objects_gt(const std::filesystem::path& file,
                                             const std::string& default_class) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string(), kCannotOpenGt);
  require(!default_class.empty(), "--gt-class", "must not be empty");
  // Detect by content: JSON starts with '{' (after blanks); anything else is the cuboid text.
  char first = 0;
  while (in.get(first) && std::isspace(static_cast<unsigned char>(first))) {
  }
  in.close();
  if (first == '{') return read_objects_gt_json(file);
  return read_objects_gt_cuboids(file, default_class);
}

std::vector<ReferenceObject> to_reference(const std::vector<io::MappedObject>& objects) {
  std::vector<ReferenceObject> out;
  for (const io::MappedObject& o : objects)
    out.push_back({o.id, o.class_name, o.centroid, o.obb, o.position});
  return out;
}

}  // namespace objmap::eval
