#include "objmap/io/diff_json.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>

#include "objmap/core/error.h"
#include "objmap/io/json_file.h"

namespace objmap::io {

namespace {

using nlohmann::json;

// The file and a field of it: "d/diff.json: objects[2].before".
struct Field {
  const std::string& file;
  std::string path;  // "" at the top level
  Field operator/(const std::string& key) const {
    return {file, path.empty() ? key : path + "." + key};
  }
  Field operator[](std::size_t i) const { return {file, path + "[" + std::to_string(i) + "]"}; }
  std::string where() const { return path.empty() ? file : file + ": " + path; }
  [[noreturn]] void fail(const std::string& reason) const { throw InputError(where(), reason); }
};

// A value for a message: its JSON text, cut short.
std::string shown(const json& v) {
  std::string text = v.dump(-1, ' ', false, json::error_handler_t::replace);
  if (text.size() > 40) text = text.substr(0, 37) + "...";
  return text;
}

const json& member(const json& j, const std::string& key, const Field& at) {
  if (!j.is_object()) at.fail("expected an object, got " + shown(j));
  if (!j.contains(key)) at.fail("missing field '" + key + "'");
  return j[key];
}

double number(const json& v, const Field& at, double lo = -HUGE_VAL, double hi = HUGE_VAL) {
  if (!v.is_number()) at.fail("expected a number, got " + shown(v));
  const double x = v.get<double>();
  if (!std::isfinite(x) || x < lo || x > hi) {
    std::string range = lo == 0 && hi == 1 ? "in [0, 1]" : lo == 0 ? "≥ 0" : "finite";
    at.fail("expected a number " + range + ", got " + shown(v));
  }
  return x;
}

std::optional<double> number_or_null(const json& v, const Field& at) {
  if (v.is_null()) return std::nullopt;
  return number(v, at, 0.0);
}

int integer(const json& v, const Field& at, bool non_negative) {
  if (!v.is_number_integer() || v.get<double>() < (non_negative ? 0 : INT32_MIN) ||
      v.get<double>() > INT32_MAX)
    at.fail(std::string("expected ") + (non_negative ? "an integer ≥ 0" : "an integer") + ", got " +
            shown(v));
  return v.get<int>();
}

std::string text(const json& v, const Field& at) {
  if (!v.is_string()) at.fail("expected a string, got " + shown(v));
  return v.get<std::string>();
}

Vec3 vec3(const json& v, const Field& at) {
  if (!v.is_array() || v.size() != 3) at.fail("expected [x, y, z], got " + shown(v));
  return {number(v[0], at[0]), number(v[1], at[1]), number(v[2], at[2])};
}

// 16 numbers, row-major, a rigid transform (rotation orthonormal within 1e-3, last row 0 0 0 1).
Pose rigid_matrix(const json& v, const Field& at) {
  if (!v.is_array() || v.size() != 16)
    at.fail("expected 16 numbers (4x4, row-major), got " + shown(v));
  Eigen::Matrix4d m;
  for (int k = 0; k < 16; ++k) m(k / 4, k % 4) = number(v[k], at[k]);
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  const bool rotation =
      (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-3 &&
      r.determinant() > 0;
  if (!rotation || !m.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1)))
    at.fail("not a rigid transform; expected a rotation and a translation, last row 0 0 0 1");
  Pose p = Pose::Identity();
  p.linear() = r;
  p.translation() = m.topRightCorner<3, 1>();
  return p;
}

DiffRegistration read_registration(const json& r, const Field& at) {
  const auto get = [&](const char* key) -> const json& { return member(r, key, at); };
  DiffRegistration g;
  g.source = text(get("source"), at / "source");
  if (g.source != "objects+icp" && g.source != "given")
    (at / "source").fail("'" + g.source + "'; expected objects+icp or given");
  g.before_from_after = rigid_matrix(get("before_from_after"), at / "before_from_after");
  g.yaw_deg = number(get("yaw_deg"), at / "yaw_deg");
  g.tilt_deg = number(get("tilt_deg"), at / "tilt_deg", 0.0);
  g.translation_m = vec3(get("translation_m"), at / "translation_m");
  g.common_objects = integer(get("common_objects"), at / "common_objects", true);
  g.coarse_rms_m = number(get("coarse_rms_m"), at / "coarse_rms_m", 0.0);
  g.hypotheses = integer(get("hypotheses"), at / "hypotheses", true);
  g.fitness = number(get("fitness"), at / "fitness", 0.0, 1.0);
  g.fitness_both = number(get("fitness_both"), at / "fitness_both", 0.0, 1.0);
  g.rms_m = number(get("rms_m"), at / "rms_m", 0.0);
  g.icp_points = integer(get("icp_points"), at / "icp_points", true);
  g.sigma_translation_m = number_or_null(get("sigma_translation_m"), at / "sigma_translation_m");
  g.sigma_yaw_deg = number_or_null(get("sigma_yaw_deg"), at / "sigma_yaw_deg");
  g.uncertainty_at_objects_m =
      number_or_null(get("uncertainty_at_objects_m"), at / "uncertainty_at_objects_m");
  g.uncertainty_yaw_deg = number_or_null(get("uncertainty_yaw_deg"), at / "uncertainty_yaw_deg");
  return g;
}

std::optional<DiffSide> read_side(const json& s, const Field& at, const Pose& before_from_after,
                                  bool after) {
  if (s.is_null()) return std::nullopt;
  DiffSide side;
  side.id = integer(member(s, "id", at), at / "id", false);
  side.class_name = text(member(s, "class", at), at / "class");
  side.position = vec3(member(s, "position", at), at / "position");
  side.position_in_before = after ? Vec3(before_from_after * side.position) : side.position;
  if (s.contains("position_in_before"))
    side.position_in_before = vec3(s["position_in_before"], at / "position_in_before");
  return side;
}

std::optional<DiffEvidence> read_evidence(const json& e, const Field& at) {
  if (e.is_null()) return std::nullopt;
  const auto count = [&](const char* key) { return integer(member(e, key, at), at / key, true); };
  DiffEvidence d;
  d.views = count("views");
  d.sightlines = count("sightlines");
  d.surface = count("surface");
  d.seen_through = count("seen_through");
  d.occluded = count("occluded");
  d.surface_share = number(member(e, "surface_share", at), at / "surface_share", 0.0, 1.0);
  return d;
}

// The sides a status needs: moved both; removed, not_seen_again a before side; added,
// not_seen_before an after side; the others at least one.
void check_sides(const DiffObject& o, const Field& at) {
  const std::string& s = o.status;
  if ((s == "moved" || s == "removed" || s == "not_seen_again") && !o.before)
    (at / "before").fail("null; status " + s + " needs a before side");
  if ((s == "moved" || s == "added" || s == "not_seen_before") && !o.after)
    (at / "after").fail("null; status " + s + " needs an after side");
  if (!o.before && !o.after) at.fail("both sides null; expected at least one");
  if (s == "moved" && !o.displacement_m)
    (at / "displacement_m").fail("null; status moved needs its displacement");
}

DiffObject read_object(const json& j, const Field& at, const Pose& before_from_after) {
  DiffObject o;
  o.status = text(member(j, "status", at), at / "status");
  if (std::none_of(kDiffStatuses.begin(), kDiffStatuses.end(),
                   [&](const char* s) { return o.status == s; }))
    (at / "status")
        .fail("'" + o.status +
              "'; expected one of unchanged, moved, removed, added, "
              "changed_class, not_seen_again, not_seen_before");
  o.before = read_side(member(j, "before", at), at / "before", before_from_after, false);
  o.after = read_side(member(j, "after", at), at / "after", before_from_after, true);
  o.distance_m = number_or_null(member(j, "distance_m", at), at / "distance_m");
  const json& d = member(j, "displacement_m", at);
  if (!d.is_null()) o.displacement_m = vec3(d, at / "displacement_m");
  const json& e = member(j, "evidence", at);
  o.after_visit =
      read_evidence(member(e, "after_visit", at / "evidence"), at / "evidence" / "after_visit");
  o.before_visit =
      read_evidence(member(e, "before_visit", at / "evidence"), at / "evidence" / "before_visit");
  o.why = text(member(j, "why", at), at / "why");
  check_sides(o, at);
  return o;
}

void read_counts(const json& c, const Field& at, DiffFile& d) {
  if (!c.is_object()) at.fail("expected an object, got " + shown(c));
  for (const char* s : kDiffStatuses) member(c, s, at);
  for (const auto& [key, value] : c.items()) d.counts[key] = integer(value, at / key, true);
}

void read_left_out(const json& l, const Field& at, DiffFile& d) {
  if (!l.is_array()) at.fail("expected an array, got " + shown(l));
  for (std::size_t i = 0; i < l.size(); ++i) {
    const std::string cls = text(member(l[i], "class", at[i]), at[i] / "class");
    const int n = integer(member(l[i], "count", at[i]), at[i] / "count", true);
    if (n < 1) (at[i] / "count").fail("0; expected at least 1");
    d.left_out.emplace_back(cls, n);
  }
}

}  // namespace

const Vec3& DiffObject::position_in_before() const {
  return before ? before->position : after->position_in_before;
}

DiffFile read_diff_json(const std::filesystem::path& path) {
  DiffFile d;
  std::error_code ec;
  d.source = (std::filesystem::is_directory(path, ec) ? path / "diff.json" : path).string();
  const json doc = read_json_file(d.source, "cannot open; expected the diff.json of objmap diff");
  const Field top{d.source, ""};
  if (!doc.is_object()) top.fail("expected a JSON object (the diff.json of objmap diff)");
  const json& version = member(doc, "schema_version", top);
  if (version != 1) (top / "schema_version").fail(shown(version) + "; expected 1");
  d.generator = text(member(doc, "generator", top), top / "generator");
  d.before = text(member(doc, "before", top), top / "before");
  d.after = text(member(doc, "after", top), top / "after");
  d.frame = text(member(doc, "frame", top), top / "frame");
  d.registration = read_registration(member(doc, "registration", top), top / "registration");
  read_counts(member(doc, "counts", top), top / "counts", d);
  read_left_out(member(doc, "left_out", top), top / "left_out", d);
  const json& objects = member(doc, "objects", top);
  if (!objects.is_array()) (top / "objects").fail("expected an array, got " + shown(objects));
  for (std::size_t i = 0; i < objects.size(); ++i)
    d.objects.push_back(
        read_object(objects[i], (top / "objects")[i], d.registration.before_from_after));
  return d;
}

}  // namespace objmap::io
