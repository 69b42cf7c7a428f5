#include "objmap/eval/diff.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "objmap/core/error.h"
#include "objmap/io/json_file.h"

namespace objmap::eval {

namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;

// One change of either file: its kind and its positions (before world, after world).
struct Change {
  std::string kind;  // moved, added, removed (others are not scored)
  std::optional<Vec3> before, after;
};

const json& member(const json& node, const std::string& key, const fs::path& file,
                   const std::string& where) {
  const std::string name = where.empty() ? key : where + "." + key;
  require(node.is_object() && node.contains(key), file.string() + ": " + name,
          "missing; expected the field objmap writes there");
  return node.at(key);
}

std::optional<Vec3> position(const json& node, const fs::path& file, const std::string& where) {
  if (node.is_null()) return std::nullopt;
  require(node.is_array() && node.size() == 3 && node[0].is_number() && node[1].is_number() &&
              node[2].is_number(),
          file.string() + ": " + where, "expected 3 numbers or null");
  return Vec3(node[0].get<double>(), node[1].get<double>(), node[2].get<double>());
}

Pose matrix(const json& node, const fs::path& file, const std::string& where) {
  require(node.is_array() && node.size() == 16, file.string() + ": " + where,
          "expected 16 numbers (a row-major 4x4 matrix)");
  Pose p = Pose::Identity();
  for (int k = 0; k < 16; ++k) {
    require(node[k].is_number(), file.string() + ": " + where, "expected 16 numbers");
    p.matrix()(k / 4, k % 4) = node[k].get<double>();
  }
  return p;
}

std::string kind_of(const std::string& status) { return status == "changed_class" ? "" : status; }

// diff.json: before_from_after and its changes.
Pose read_diff(const fs::path& file, std::vector<Change>& changes, int& not_seen) {
  const json doc = io::read_json_file(file, "cannot open; expected the diff.json of objmap diff");
  const Pose est = matrix(
      member(member(doc, "registration", file, ""), "before_from_after", file, "registration"),
      file, "registration.before_from_after");
  const json& objects = member(doc, "objects", file, "");
  require(objects.is_array(), file.string() + ": objects", "expected an array");
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const std::string where = "objects[" + std::to_string(i) + "]";
    const json& s = member(objects[i], "status", file, where);
    require(s.is_string(), file.string() + ": " + where + ".status", "expected a string");
    const std::string status = s.get<std::string>();
    if (status.rfind("not_seen", 0) == 0) ++not_seen;
    Change c{kind_of(status), std::nullopt, std::nullopt};
    const json& b = member(objects[i], "before", file, where);
    const json& a = member(objects[i], "after", file, where);
    if (!b.is_null())
      c.before = position(member(b, "position", file, where + ".before"), file,
                          where + ".before.position");
    if (!a.is_null())
      c.after =
          position(member(a, "position", file, where + ".after"), file, where + ".after.position");
    changes.push_back(c);
  }
  return est;
}

// changes_gt.json: before_from_after and the true changes.
Pose read_truth(const fs::path& file, std::vector<Change>& changes) {
  const json doc =
      io::read_json_file(file, "cannot open; expected the changes_gt.json of objmap synth");
  const Pose truth = matrix(member(doc, "before_from_after", file, ""), file, "before_from_after");
  const json& objects = member(doc, "objects", file, "");
  require(objects.is_array(), file.string() + ": objects", "expected an array");
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const std::string where = "objects[" + std::to_string(i) + "]";
    const json& s = member(objects[i], "status", file, where);
    require(s.is_string(), file.string() + ": " + where + ".status", "expected a string");
    changes.push_back({kind_of(s.get<std::string>()),
                       position(member(objects[i], "before_position", file, where), file,
                                where + ".before_position"),
                       position(member(objects[i], "after_position", file, where), file,
                                where + ".after_position")});
  }
  return truth;
}

// Found changes of `kind` matched one-to-one to true ones, nearest first.
ChangeScore score(const std::vector<Change>& found, const std::vector<Change>& truth,
                  const std::string& kind, double match_m) {
  const auto distance = [&](const Change& f, const Change& t) {
    double d = 0.0;
    if (kind != "added") {  // moved and removed: the before end
      if (!f.before || !t.before) return HUGE_VAL;
      d = std::max(d, (*f.before - *t.before).norm());
    }
    if (kind != "removed") {  // moved and added: the after end
      if (!f.after || !t.after) return HUGE_VAL;
      d = std::max(d, (*f.after - *t.after).norm());
    }
    return d;
  };
  ChangeScore s;
  std::vector<std::tuple<double, int, int>> pairs;
  std::vector<int> fi, ti;
  for (int i = 0; i < static_cast<int>(found.size()); ++i)
    if (found[i].kind == kind) fi.push_back(i);
  for (int j = 0; j < static_cast<int>(truth.size()); ++j)
    if (truth[j].kind == kind) ti.push_back(j);
  s.found = static_cast<int>(fi.size());
  s.truth = static_cast<int>(ti.size());
  for (int i : fi)
    for (int j : ti)
      if (const double d = distance(found[i], truth[j]); d <= match_m) pairs.emplace_back(d, i, j);
  std::sort(pairs.begin(), pairs.end());
  std::vector<bool> used_f(found.size()), used_t(truth.size());
  for (const auto& [d, i, j] : pairs)
    if (!used_f[i] && !used_t[j]) used_f[i] = used_t[j] = true, ++s.correct;
  return s;
}

}  // namespace

void DiffEvalOptions::check() const {
  require(std::isfinite(match_m) && match_m > 0.0, "DiffEvalOptions.match_m", "must be > 0");
}

double ChangeScore::f1() const {
  const double p = precision(), r = recall();
  return p + r > 0 ? 2 * p * r / (p + r) : 0.0;
}

ChangeScore DiffEvalResult::all() const {
  ChangeScore s;
  for (const ChangeScore* c : {&moved, &added, &removed}) {
    s.truth += c->truth;
    s.found += c->found;
    s.correct += c->correct;
  }
  return s;
}

DiffEvalResult evaluate_diff(const fs::path& diff_json, const fs::path& changes_gt_json,
                             const DiffEvalOptions& options) {
  options.check();
  std::vector<Change> found, truth;
  DiffEvalResult r;
  const Pose est = read_diff(diff_json, found, r.not_seen);
  const Pose gt = read_truth(changes_gt_json, truth);
  // Registration: rotation angle and translation of gt⁻¹·est, and the error at the objects.
  const Pose e = gt.inverse() * est;
  r.rotation_error_deg = Eigen::AngleAxisd(e.linear()).angle() * 180.0 / M_PI;
  r.translation_error_m = e.translation().norm();
  double sum2 = 0.0;
  int n = 0;
  for (const Change& c : truth)
    if (c.after) sum2 += (est * *c.after - gt * *c.after).squaredNorm(), ++n;
  r.error_at_objects_m = n ? std::sqrt(sum2 / n) : 0.0;
  r.moved = score(found, truth, "moved", options.match_m);
  r.added = score(found, truth, "added", options.match_m);
  r.removed = score(found, truth, "removed", options.match_m);
  return r;
}

std::string diff_eval_json(const DiffEvalResult& r, const DiffEvalOptions& options) {
  using ordered = nlohmann::ordered_json;
  const auto score_json = [](const ChangeScore& s) {
    return ordered{{"truth", s.truth},           {"found", s.found},     {"correct", s.correct},
                   {"precision", s.precision()}, {"recall", s.recall()}, {"f1", s.f1()}};
  };
  ordered doc = {{"registration",
                  {{"rotation_error_deg", r.rotation_error_deg},
                   {"error_at_objects_m", r.error_at_objects_m},
                   {"translation_error_m", r.translation_error_m}}},
                 {"moved", score_json(r.moved)},
                 {"added", score_json(r.added)},
                 {"removed", score_json(r.removed)},
                 {"all", score_json(r.all())},
                 {"not_seen", r.not_seen},
                 {"match_m", options.match_m}};
  return doc.dump(2) + "\n";
}

}  // namespace objmap::eval
