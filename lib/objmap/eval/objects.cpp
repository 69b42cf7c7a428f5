#include "objmap/eval/objects.h"

#include "objmap/core/json_vec.h"
#include "objmap/track/assignment.h"

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
#include "objmap/eval/json.h"
#include "objmap/io/json_file.h"
#include "objmap/io/text_lines.h"
#include "objmap/segmentation/coco_classes.h"

namespace objmap::eval {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

// ---- assignment
// ---------------------------------------------------------------------------------

std::vector<int> hungarian_assign(const Eigen::MatrixXd& cost) {
  const int rows = static_cast<int>(cost.rows()), cols = static_cast<int>(cost.cols());
  std::vector<int> row_to_col(rows, -1);
  if (rows == 0 || cols == 0) return row_to_col;
  // Forbidden pairs get a cost BIG larger than any sum of min(rows, cols) allowed costs (after
  // shifting them to >= 0), so that the optimum first has the fewest forbidden pairs, then the
  // least total cost; the shared Kuhn-Munkres (track/assignment.h) solves that finite problem.
  double min_allowed = kInf, max_allowed = -kInf;
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j)
      if (std::isfinite(cost(i, j))) {
        min_allowed = std::min(min_allowed, cost(i, j));
        max_allowed = std::max(max_allowed, cost(i, j));
      }
  if (!std::isfinite(min_allowed)) return row_to_col;  // nothing allowed
  const double big = (max_allowed - min_allowed + 1.0) * (std::min(rows, cols) + 1);
  Eigen::MatrixXd finite(rows, cols);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j)
      finite(i, j) = std::isfinite(cost(i, j)) ? cost(i, j) - min_allowed : big;
  const std::vector<int> assigned = track::solve_assignment(finite);
  for (int i = 0; i < rows; ++i)
    if (assigned[i] >= 0 && std::isfinite(cost(i, assigned[i]))) row_to_col[i] = assigned[i];
  return row_to_col;
}

// ---- oriented boxes
// -----------------------------------------------------------------------------

namespace {

using Polygon = std::vector<Vec3>;  // a convex planar polygon, vertices in cyclic order

// The six faces of a box, each as 4 corners in cyclic order.
std::vector<Polygon> box_faces(const Obb& box) {
  std::vector<Polygon> faces;
  for (int axis = 0; axis < 3; ++axis) {
    const int j = (axis + 1) % 3, k = (axis + 2) % 3;
    for (const double side : {-1.0, 1.0}) {
      Polygon face;
      const double sj[4] = {-1, 1, 1, -1}, sk[4] = {-1, -1, 1, 1};
      for (int corner = 0; corner < 4; ++corner) {
        Vec3 local = Vec3::Zero();
        local[axis] = side * box.half_extent[axis];
        local[j] = sj[corner] * box.half_extent[j];
        local[k] = sk[corner] * box.half_extent[k];
        face.push_back(box.center + box.rotation * local);
      }
      faces.push_back(face);
    }
  }
  return faces;
}

// Keeps the part of the convex polyhedron `faces` where normal·x <= offset; closes the cut with a
// cap polygon. `eps` is the distance under which a point counts as on the plane.
std::vector<Polygon> clip_polyhedron(const std::vector<Polygon>& faces, const Vec3& normal,
                                     double offset, double eps) {
  std::vector<Polygon> out;
  std::vector<Vec3> cap;
  bool face_in_plane = false;
  for (const Polygon& face : faces) {
    Polygon kept;
    const std::size_t k = face.size();
    for (std::size_t i = 0; i < k; ++i) {
      const Vec3& cur = face[i];
      const Vec3& next = face[(i + 1) % k];
      const double dc = normal.dot(cur) - offset, dn = normal.dot(next) - offset;
      if (dc <= eps) {
        kept.push_back(cur);
        if (dc >= -eps) cap.push_back(cur);
      }
      if ((dc < -eps && dn > eps) || (dc > eps && dn < -eps)) {
        const Vec3 p = cur + (dc / (dc - dn)) * (next - cur);
        kept.push_back(p);
        cap.push_back(p);
      }
    }
    if (kept.size() < 3) continue;
    // A face lying in the plane already closes the cut: no cap then.
    bool in_plane = true;
    for (const Vec3& p : kept) in_plane = in_plane && std::abs(normal.dot(p) - offset) <= eps;
    face_in_plane = face_in_plane || in_plane;
    out.push_back(std::move(kept));
  }
  if (face_in_plane) return out;
  // The cap: the distinct points on the plane, in angular order around their mean.
  std::vector<Vec3> unique;
  for (const Vec3& p : cap) {
    bool seen = false;
    for (const Vec3& q : unique) seen = seen || (p - q).norm() <= 10 * eps;
    if (!seen) unique.push_back(p);
  }
  if (unique.size() >= 3) {
    Vec3 mean = Vec3::Zero();
    for (const Vec3& p : unique) mean += p;
    mean /= static_cast<double>(unique.size());
    const Vec3 e1 = normal.unitOrthogonal(), e2 = normal.cross(e1);
    std::vector<std::pair<double, Vec3>> by_angle;
    for (const Vec3& p : unique)
      by_angle.push_back({std::atan2(e2.dot(p - mean), e1.dot(p - mean)), p});
    std::sort(by_angle.begin(), by_angle.end(),
              [](const auto& x, const auto& y) { return x.first < y.first; });
    Polygon polygon;
    for (const auto& entry : by_angle) polygon.push_back(entry.second);
    out.push_back(std::move(polygon));
  }
  return out;
}

// Volume of a convex polyhedron given by its face polygons: pyramids from an interior point.
double polyhedron_volume(const std::vector<Polygon>& faces) {
  Vec3 inside = Vec3::Zero();
  std::size_t count = 0;
  for (const Polygon& face : faces)
    for (const Vec3& p : face) {
      inside += p;
      ++count;
    }
  if (count == 0) return 0.0;
  inside /= static_cast<double>(count);
  double volume = 0.0;
  for (const Polygon& face : faces) {
    Vec3 area2 = Vec3::Zero();  // twice the vector area
    for (std::size_t i = 1; i + 1 < face.size(); ++i)
      area2 += (face[i] - face[0]).cross(face[i + 1] - face[0]);
    volume += std::abs(area2.dot(face[0] - inside)) / 6.0;
  }
  return volume;
}

}  // namespace

double obb_volume(const Obb& box) {
  return 8.0 * std::max(0.0, box.half_extent.x()) * std::max(0.0, box.half_extent.y()) *
         std::max(0.0, box.half_extent.z());
}

double obb_intersection_volume(const Obb& a, const Obb& b) {
  if (obb_volume(a) <= 0.0 || obb_volume(b) <= 0.0) return 0.0;
  // Bounding spheres apart: no overlap.
  if ((a.center - b.center).norm() > a.half_extent.norm() + b.half_extent.norm()) return 0.0;
  const double scale =
      1.0 + a.center.norm() + b.center.norm() + a.half_extent.norm() + b.half_extent.norm();
  const double eps = 1e-12 * scale;
  std::vector<Polygon> faces = box_faces(a);
  for (int axis = 0; axis < 3 && !faces.empty(); ++axis)
    for (const double side : {-1.0, 1.0}) {
      // Half-space of b: side · axis_b · (x − c_b) <= h_b[axis].
      const Vec3 normal = side * b.rotation.col(axis);
      const double offset = normal.dot(b.center) + b.half_extent[axis];
      faces = clip_polyhedron(faces, normal, offset, eps);
      if (faces.size() < 4) return 0.0;  // nothing with volume left
    }
  return std::min(polyhedron_volume(faces), std::min(obb_volume(a), obb_volume(b)));
}

double obb_iou(const Obb& a, const Obb& b) {
  const double inter = obb_intersection_volume(a, b);
  const double uni = obb_volume(a) + obb_volume(b) - inter;
  if (uni <= 0.0) return 0.0;
  return std::clamp(inter / uni, 0.0, 1.0);
}

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

// ---- the evaluation
// -----------------------------------------------------------------------------

void ObjectEvalOptions::check() const {
  require(std::isfinite(gate_m) && gate_m > 0, "ObjectEvalOptions.gate_m",
          "must be > 0 metres, got " + number_text(gate_m));
  for (const double t : thresholds_m)
    require(std::isfinite(t) && t > 0, "ObjectEvalOptions.thresholds_m",
            "must be > 0 metres, got " + number_text(t));
}

namespace {

struct ClassMembers {
  std::vector<std::size_t> map, reference;  // indices into the inputs
};

// The objects' indices on both sides per canonical class, sorted by class name.
std::map<std::string, ClassMembers> members_by_class(
    const std::vector<io::MappedObject>& map, const std::vector<ReferenceObject>& reference) {
  std::map<std::string, ClassMembers> classes;
  for (std::size_t i = 0; i < map.size(); ++i)
    classes[segmentation::canonical_class(map[i].class_name)].map.push_back(i);
  for (std::size_t j = 0; j < reference.size(); ++j)
    classes[segmentation::canonical_class(reference[j].class_name)].reference.push_back(j);
  return classes;
}

// Pairs (map index, reference index) of the one-to-one assignment within `gate_m`.
std::vector<std::pair<std::size_t, std::size_t>> assign_class(
    const ClassMembers& members, const std::vector<io::MappedObject>& map,
    const std::vector<ReferenceObject>& reference, double gate_m) {
  Eigen::MatrixXd cost(members.map.size(), members.reference.size());
  for (std::size_t i = 0; i < members.map.size(); ++i)
    for (std::size_t j = 0; j < members.reference.size(); ++j) {
      const double d =
          (map[members.map[i]].centroid - reference[members.reference[j]].centroid).norm();
      cost(i, j) = d <= gate_m ? d : kInf;
    }
  const std::vector<int> row_to_col = hungarian_assign(cost);
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < row_to_col.size(); ++i)
    if (row_to_col[i] >= 0) pairs.push_back({members.map[i], members.reference[row_to_col[i]]});
  return pairs;
}

ObjectMatch make_match(const io::MappedObject& m, const ReferenceObject& r,
                       const std::string& class_name) {
  ObjectMatch match;
  match.map_id = m.id;
  match.reference_id = r.id;
  match.class_name = class_name;
  match.error_xyz_m = m.centroid - r.centroid;
  match.distance_m = match.error_xyz_m.norm();
  match.iou = obb_iou(m.obb, r.obb);
  match.position_distance_m = (m.position - r.position).norm();
  return match;
}

bool by_reference_id(const ObjectMatch& a, const ObjectMatch& b) {
  return std::tie(a.reference_id, a.map_id) < std::tie(b.reference_id, b.map_id);
}

// Table 3: a row per class, then "overall".
std::vector<CountRow> count_rows(const std::map<std::string, ClassMembers>& classes,
                                 std::size_t mapped, std::size_t reference) {
  const auto count_row = [](const std::string& name, std::size_t map_count, std::size_t ref) {
    CountRow row{name, map_count, ref, std::nullopt};
    if (ref > 0)
      row.error = std::abs(static_cast<double>(map_count) - static_cast<double>(ref)) /
                  static_cast<double>(ref);
    return row;
  };
  std::vector<CountRow> rows;
  for (const auto& [name, members] : classes)
    rows.push_back(count_row(name, members.map.size(), members.reference.size()));
  rows.push_back(count_row("overall", mapped, reference));
  return rows;
}

// The pairs within the gate, then the left-over objects paired without a gate (beyond_gate), the
// unmatched and missed ids and every reference object's outcome.
void pair_objects(const std::map<std::string, ClassMembers>& classes,
                  const std::vector<io::MappedObject>& map,
                  const std::vector<ReferenceObject>& reference, double gate_m,
                  ObjectEvalResult& result) {
  std::vector<char> map_matched(map.size(), 0), ref_matched(reference.size(), 0);
  std::vector<ReferenceOutcome> outcomes;  // per reference index
  for (const ReferenceObject& r : reference)
    outcomes.push_back({r.id, segmentation::canonical_class(r.class_name), "missed", std::nullopt});
  for (const auto& [name, members] : classes) {
    for (const auto& [i, j] : assign_class(members, map, reference, gate_m)) {
      result.matches.push_back(make_match(map[i], reference[j], name));
      outcomes[j].status = "matched";
      outcomes[j].match = result.matches.back();
      map_matched[i] = ref_matched[j] = 1;
    }
    ClassMembers left;
    for (const std::size_t i : members.map)
      if (!map_matched[i]) left.map.push_back(i);
    for (const std::size_t j : members.reference)
      if (!ref_matched[j]) left.reference.push_back(j);
    for (const auto& [i, j] : assign_class(left, map, reference, kInf)) {
      result.beyond_gate.push_back(make_match(map[i], reference[j], name));
      outcomes[j].status = "beyond_gate";
      outcomes[j].match = result.beyond_gate.back();
    }
  }
  std::sort(result.matches.begin(), result.matches.end(), by_reference_id);
  std::sort(result.beyond_gate.begin(), result.beyond_gate.end(), by_reference_id);
  for (std::size_t i = 0; i < map.size(); ++i)
    if (!map_matched[i]) result.unmatched_map_ids.push_back(map[i].id);
  for (std::size_t j = 0; j < reference.size(); ++j) {
    if (!ref_matched[j]) result.unmatched_reference_ids.push_back(reference[j].id);
    if (!outcomes[j].match) result.missed_reference_ids.push_back(reference[j].id);
  }
  std::sort(result.unmatched_map_ids.begin(), result.unmatched_map_ids.end());
  std::sort(result.unmatched_reference_ids.begin(), result.unmatched_reference_ids.end());
  std::sort(result.missed_reference_ids.begin(), result.missed_reference_ids.end());
  std::stable_sort(outcomes.begin(), outcomes.end(),
                   [](const ReferenceOutcome& a, const ReferenceOutcome& b) {
                     return a.reference_id < b.reference_id;
                   });
  result.reference_objects = std::move(outcomes);
}

// Tables 4–5, one row: the pairs within the gate, the pairs beyond it, the missed objects.
ErrorRow error_row(const std::string& name, std::size_t mapped, std::size_t reference,
                   const std::vector<const ObjectMatch*>& matches,
                   const std::vector<const ObjectMatch*>& beyond, double gate_m) {
  ErrorRow row;
  row.class_name = name;
  row.mapped = mapped;
  row.reference = reference;
  row.matched = matches.size();
  row.beyond_gate = beyond.size();
  row.missed = reference - matches.size() - beyond.size();
  row.false_positives = mapped - matches.size();
  std::vector<double> distances, ious, positions;
  for (const ObjectMatch* m : matches) {
    distances.push_back(m->distance_m);
    ious.push_back(m->iou);
    positions.push_back(m->position_distance_m);
    row.mean_abs_xyz_m += m->error_xyz_m.cwiseAbs();
  }
  if (!matches.empty()) row.mean_abs_xyz_m /= static_cast<double>(matches.size());
  row.distance_m = compute_stats(distances);
  row.iou = compute_stats(ious);
  row.position_distance_m = compute_stats(positions);
  for (const ObjectMatch* m : beyond) {
    distances.push_back(m->distance_m);
    ious.push_back(m->iou);
  }
  distances.insert(distances.end(), row.missed, gate_m);
  ious.insert(ious.end(), row.missed, 0.0);
  row.distance_all_m = compute_stats(distances);
  row.iou_all = compute_stats(ious);
  return row;
}

// The pairs of class `name`; all of them without a name (the "overall" row).
std::vector<const ObjectMatch*> of_class(const std::vector<ObjectMatch>& matches,
                                         const std::optional<std::string>& name) {
  std::vector<const ObjectMatch*> out;
  for (const ObjectMatch& m : matches)
    if (!name || m.class_name == *name) out.push_back(&m);
  return out;
}

}  // namespace

std::vector<std::pair<std::size_t, std::size_t>> match_by_class(
    const std::vector<io::MappedObject>& map, const std::vector<ReferenceObject>& reference,
    double gate_m) {
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (const auto& [name, members] : members_by_class(map, reference))
    for (const auto& pair : assign_class(members, map, reference, gate_m)) pairs.push_back(pair);
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

ObjectEvalResult evaluate_objects(const std::vector<io::MappedObject>& map,
                                  const std::vector<ReferenceObject>& reference,
                                  const ObjectEvalOptions& options) {
  options.check();
  const std::map<std::string, ClassMembers> classes = members_by_class(map, reference);
  ObjectEvalResult result;
  result.counts = count_rows(classes, map.size(), reference.size());
  pair_objects(classes, map, reference, options.gate_m, result);

  // Tables 4–5.
  for (const auto& [name, members] : classes)
    result.errors.push_back(error_row(name, members.map.size(), members.reference.size(),
                                      of_class(result.matches, name),
                                      of_class(result.beyond_gate, name), options.gate_m));
  result.errors.push_back(error_row("overall", map.size(), reference.size(),
                                    of_class(result.matches, std::nullopt),
                                    of_class(result.beyond_gate, std::nullopt), options.gate_m));

  // Precision / recall, each threshold with its own assignment.
  for (const double threshold : options.thresholds_m) {
    PrecisionRecall pr;
    pr.threshold_m = threshold;
    for (const auto& [name, members] : classes)
      pr.matched += assign_class(members, map, reference, threshold).size();
    if (!map.empty()) pr.precision = static_cast<double>(pr.matched) / map.size();
    if (!reference.empty()) pr.recall = static_cast<double>(pr.matched) / reference.size();
    result.precision_recall.push_back(pr);
  }
  return result;
}

// ---- Table 6
// ------------------------------------------------------------------------------------

double PointCounts::reduction() const {
  return dense_map > 0 ? 1.0 - objects_map / dense_map : 0.0;
}

double PointCounts::reduction_eq18() const {
  return objects_voxel_filtered > 0 ? 1.0 - objects_outlier_filtered / objects_voxel_filtered : 0.0;
}

PointCounts read_point_counts(const std::filesystem::path& run_json) {
  const json doc =
      io::read_json_file(run_json, "cannot open; expected RUN/run.json of objmap fuse");
  if (!doc.is_object() || !doc.contains("points") || !doc["points"].is_object())
    throw InputError(run_json.string(),
                     "missing object 'points'; expected run.json of objmap fuse "
                     "(schemas/run.schema.json)");
  const json& points = doc["points"];
  PointCounts counts;
  counts.source = run_json.string();
  const auto get = [&](const char* key, double& value) {
    if (!points.contains(key) || !points[key].is_number() || points[key].get<double>() < 0)
      throw InputError(run_json.string() + ": points." + key,
                       "missing or not a number >= 0; expected a point count");
    value = points[key].get<double>();
  };
  get("dense_back_projected", counts.dense_back_projected);
  get("dense_map", counts.dense_map);
  get("objects_raw", counts.objects_raw);
  get("objects_voxel_filtered", counts.objects_voxel_filtered);
  get("objects_outlier_filtered", counts.objects_outlier_filtered);
  get("semantic_map", counts.semantic_map);
  get("objects_map", counts.objects_map);
  return counts;
}

// ---- output
// -------------------------------------------------------------------------------------

namespace {

using nlohmann::ordered_json;

ordered_json alignment_json(const ObjectAlignment& a) {
  ordered_json out;
  out["method"] = a.method;
  if (a.method == "none") return out;
  if (a.method == "trajectory") {
    out["gt_trajectory"] = a.gt_trajectory;
    out["trajectory"] = a.trajectory;
  }
  out["pairs"] = a.pairs;
  out["rmse_m"] = a.rmse_m;
  const Eigen::Matrix3d& r = a.reference_from_map.rotation;
  ordered_json rotation = ordered_json::array();
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 3; ++col) rotation.push_back(r(row, col));
  out["rotation"] = rotation;
  out["translation_m"] = vec3_json(a.reference_from_map.translation);
  return out;
}

ordered_json counts_json(const std::vector<CountRow>& rows) {
  ordered_json counts = ordered_json::array();
  for (const CountRow& row : rows) {
    ordered_json c;
    c["class"] = row.class_name;
    c["reference"] = row.reference;
    c["mapped"] = row.mapped;
    c["error"] = row.error ? ordered_json(*row.error) : ordered_json(nullptr);
    counts.push_back(c);
  }
  return counts;
}

ordered_json errors_json(const std::vector<ErrorRow>& rows) {
  ordered_json errors = ordered_json::array();
  for (const ErrorRow& row : rows) {
    ordered_json e;
    e["class"] = row.class_name;
    e["reference"] = row.reference;
    e["mapped"] = row.mapped;
    e["matched"] = row.matched;
    e["beyond_gate"] = row.beyond_gate;
    e["missed"] = row.missed;
    e["false_positives"] = row.false_positives;
    e["distance_m"] = stats_json(row.distance_m);
    e["mean_abs_xyz_m"] = vec3_json(row.mean_abs_xyz_m);
    e["iou"] = stats_json(row.iou);
    e["distance_all_m"] = stats_json(row.distance_all_m);
    e["iou_all"] = stats_json(row.iou_all);
    e["position_distance_m"] = stats_json(row.position_distance_m);
    errors.push_back(e);
  }
  return errors;
}

ordered_json precision_recall_json(const std::vector<PrecisionRecall>& rows) {
  ordered_json pr = ordered_json::array();
  for (const PrecisionRecall& p : rows) {
    ordered_json e;
    e["threshold_m"] = p.threshold_m;
    e["matched"] = p.matched;
    e["precision"] = p.precision;
    e["recall"] = p.recall;
    pr.push_back(e);
  }
  return pr;
}

ordered_json match_json(const ObjectMatch& m) {
  ordered_json e;
  e["map_id"] = m.map_id;
  e["reference_id"] = m.reference_id;
  e["class"] = m.class_name;
  e["distance_m"] = m.distance_m;
  e["error_xyz_m"] = vec3_json(m.error_xyz_m);
  e["iou"] = m.iou;
  e["position_distance_m"] = m.position_distance_m;
  return e;
}

ordered_json matches_json(const std::vector<ObjectMatch>& matches) {
  ordered_json out = ordered_json::array();
  for (const ObjectMatch& m : matches) out.push_back(match_json(m));
  return out;
}

ordered_json reference_objects_json(const std::vector<ReferenceOutcome>& outcomes) {
  ordered_json out = ordered_json::array();
  for (const ReferenceOutcome& o : outcomes) {
    ordered_json e;
    e["reference_id"] = o.reference_id;
    e["class"] = o.class_name;
    e["status"] = o.status;
    e["map_id"] = o.match ? ordered_json(o.match->map_id) : ordered_json(nullptr);
    e["distance_m"] = o.match ? ordered_json(o.match->distance_m) : ordered_json(nullptr);
    e["iou"] = o.match ? ordered_json(o.match->iou) : ordered_json(nullptr);
    out.push_back(e);
  }
  return out;
}

ordered_json points_json(const PointCounts& p) {
  ordered_json points;
  points["run"] = p.source;
  points["dense_back_projected"] = p.dense_back_projected;
  points["dense_map"] = p.dense_map;
  points["objects_raw"] = p.objects_raw;
  points["objects_voxel_filtered"] = p.objects_voxel_filtered;
  points["objects_outlier_filtered"] = p.objects_outlier_filtered;
  points["semantic_map"] = p.semantic_map;
  points["objects_map"] = p.objects_map;
  points["reduction"] = p.reduction();
  points["reduction_eq18"] = p.reduction_eq18();
  return points;
}

}  // namespace

std::string objects_eval_json(const ObjectEvalReport& report) {
  const ObjectEvalResult& r = report.result;
  ordered_json out;
  out["mode"] = report.mode;
  out["map"] = report.map_source;
  out["reference"] = report.reference_source;
  out["gate_m"] = report.options.gate_m;
  out["unit"] = "m";
  out["alignment"] = alignment_json(report.alignment);
  out["counts"] = counts_json(r.counts);
  out["centroid_error"] = errors_json(r.errors);
  out["precision_recall"] = precision_recall_json(r.precision_recall);
  out["matches"] = matches_json(r.matches);
  out["beyond_gate"] = matches_json(r.beyond_gate);
  out["unmatched_map_ids"] = r.unmatched_map_ids;
  out["unmatched_reference_ids"] = r.unmatched_reference_ids;
  out["missed_reference_ids"] = r.missed_reference_ids;
  out["reference_objects"] = reference_objects_json(r.reference_objects);
  if (report.points) out["points"] = points_json(*report.points);
  return out.dump(2) + "\n";
}

namespace {

std::string line(const char* format, ...) __attribute__((format(printf, 1, 2)));
std::string line(const char* format, ...) {
  char buffer[512];
  va_list args;
  va_start(args, format);
  std::vsnprintf(buffer, sizeof(buffer), format, args);
  va_end(args);
  return std::string(buffer) + "\n";
}

std::string percent(double ratio) { return fixed_text(100.0 * ratio, 1) + "%"; }

std::string ids_text(const std::vector<int>& ids) {
  std::string s;
  for (const int id : ids) s += (s.empty() ? "" : " ") + std::to_string(id);
  return s.empty() ? std::string("none") : s;
}

std::string alignment_text(const ObjectAlignment& a) {
  if (a.method == "none") return "  alignment: none (the map is taken in the reference's frame)\n";
  const double angle_deg =
      Eigen::AngleAxisd(a.reference_from_map.rotation).angle() * 180.0 / 3.14159265358979323846;
  const Vec3& t = a.reference_from_map.translation;
  const std::string what = a.method == "trajectory"
                               ? "from the trajectories (" + a.trajectory + " onto " +
                                     a.gt_trajectory + "; Umeyama on " + std::to_string(a.pairs) +
                                     " associated camera positions"
                               : "from the objects (Umeyama on " + std::to_string(a.pairs) +
                                     " objects matched by class within the gate";
  return "  alignment: SE(3) " + what + ", RMSE " + fixed_text(a.rmse_m, 4) +
         " m): the map turned by " + fixed_text(angle_deg, 3) + " deg and moved by (" +
         fixed_text(t.x(), 4) + ", " + fixed_text(t.y(), 4) + ", " + fixed_text(t.z(), 4) + ") m\n";
}

std::string counts_text(const ObjectEvalResult& r, const char* ref_label) {
  std::string out = "Table 3: number of objects\n";
  out += line("  %-16s %12s %8s %8s", "class", ref_label, "mapped", "error");
  for (const CountRow& row : r.counts) {
    if (row.class_name == "overall") out += "  " + std::string(46, '-') + "\n";
    out += line("  %-16s %12zu %8zu %8s", row.class_name.c_str(), row.reference, row.mapped,
                row.error ? percent(*row.error).c_str() : "-");
  }
  return out;
}

std::string errors_text(const ObjectEvalResult& r, double gate_m) {
  std::string out =
      "Tables 4-5: centroid error [m] of the objects matched within the gate, oriented-box IoU;\n"
      "  beyond = paired beyond the gate, FP = map objects not matched within it; all = mean over\n"
      "  every reference object (beyond the gate at its distance, a miss at the gate, " +
      number_text(gate_m) + " m)\n";
  out +=
      line("  %-16s %7s %6s %6s %4s %8s %8s %8s %7s %7s %7s %6s %8s", "class", "matched", "beyond",
           "missed", "FP", "mean", "median", "max", "|dx|", "|dy|", "|dz|", "IoU", "all");
  for (const ErrorRow& row : r.errors) {
    if (row.class_name == "overall") out += "  " + std::string(114, '-') + "\n";
    const std::string matched = std::to_string(row.matched) + "/" + std::to_string(row.reference);
    const std::string all = row.reference ? fixed_text(row.distance_all_m.mean, 4) : "-";
    if (row.matched == 0) {
      out += line("  %-16s %7s %6zu %6zu %4zu %8s %8s %8s %7s %7s %7s %6s %8s",
                  row.class_name.c_str(), matched.c_str(), row.beyond_gate, row.missed,
                  row.false_positives, "-", "-", "-", "-", "-", "-", "-", all.c_str());
      continue;
    }
    out += line("  %-16s %7s %6zu %6zu %4zu %8.4f %8.4f %8.4f %7.4f %7.4f %7.4f %6.3f %8s",
                row.class_name.c_str(), matched.c_str(), row.beyond_gate, row.missed,
                row.false_positives, row.distance_m.mean, row.distance_m.median, row.distance_m.max,
                row.mean_abs_xyz_m.x(), row.mean_abs_xyz_m.y(), row.mean_abs_xyz_m.z(),
                row.iou.mean, all.c_str());
  }
  if (!r.errors.empty() && r.errors.back().matched > 0) {
    const ErrorStats& p = r.errors.back().position_distance_m;
    out += line(
        "  position (the map's box centre) to the reference's box centre [m], overall: "
        "mean %.4f, median %.4f, max %.4f",
        p.mean, p.median, p.max);
  }
  return out;
}

std::string outcomes_text(const ObjectEvalResult& r, const char* ref_label) {
  std::string out = std::string("Every ") + ref_label +
                    " object: matched within the gate, beyond it (with its distance), or missed\n";
  out +=
      line("  %6s  %-16s %-12s %7s %12s %6s", "id", "class", "status", "map id", "distance", "IoU");
  for (const ReferenceOutcome& o : r.reference_objects) {
    if (!o.match) {
      out += line("  %6d  %-16s %-12s %7s %12s %6s", o.reference_id, o.class_name.c_str(),
                  o.status.c_str(), "-", "-", "-");
      continue;
    }
    out += line("  %6d  %-16s %-12s %7d %12.4f %6.3f", o.reference_id, o.class_name.c_str(),
                o.status.c_str(), o.match->map_id, o.match->distance_m, o.match->iou);
  }
  out += "False positives (map objects not matched within the gate): " +
         ids_text(r.unmatched_map_ids) + "\n";
  return out;
}

std::string points_text(const PointCounts& p) {
  std::string out = "Table 6: points (" + p.source + ")\n";
  const char* row = "  %-46s %12.0f";
  const char* text_row = "  %-46s %12s";
  if (p.dense_map > 0)
    out += line(row, "dense map", p.dense_map);
  else
    out += line(text_row, "dense map", "none");
  out += line(row, "objects-only map", p.objects_map);
  out += line(text_row, "reduction, objects-only vs dense map (Table 6)",
              p.dense_map > 0 ? percent(p.reduction()).c_str() : "n/a");
  out += line(row, "dense points back-projected", p.dense_back_projected);
  out += line(row, "object points raw", p.objects_raw);
  out += line(row, "object points voxel-filtered", p.objects_voxel_filtered);
  out += line(row, "object points outlier-filtered (eq 18)", p.objects_outlier_filtered);
  out += line(text_row, "eq 18 reduction (voxel- to outlier-filtered)",
              p.objects_voxel_filtered > 0 ? percent(p.reduction_eq18()).c_str() : "n/a");
  return out;
}

}  // namespace

std::string objects_eval_text(const ObjectEvalReport& report) {
  const ObjectEvalResult& r = report.result;
  const bool gt = report.mode == "ground_truth";
  const char* ref_label = gt ? "ground truth" : "reference";
  std::string out;
  out += "Objects  " + report.map_source + "\n";
  out += std::string("  vs     ") + report.reference_source +
         (gt ? " (ground-truth objects)\n" : " (reference map, ground-truth trajectory)\n");
  out += "  one-to-one by canonical class (Hungarian on centroid distance), gate " +
         number_text(report.options.gate_m) + " m\n";
  out += alignment_text(report.alignment) + "\n";
  out += counts_text(r, ref_label) + "\n";
  out += errors_text(r, report.options.gate_m) + "\n";
  out += "Precision / recall (one-to-one by class within the distance)\n";
  out += line("  %-10s %8s %10s %8s", "within", "matched", "precision", "recall");
  for (const PrecisionRecall& p : r.precision_recall)
    out += line("  %-10s %8zu %10.3f %8.3f", (fixed_text(p.threshold_m, 2) + " m").c_str(),
                p.matched, p.precision, p.recall);
  out += "\n" + outcomes_text(r, gt ? "ground-truth" : "reference");
  if (report.points) out += "\n" + points_text(*report.points);
  return out;
}

}  // namespace objmap::eval
