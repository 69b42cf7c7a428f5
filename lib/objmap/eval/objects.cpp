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

namespace {

using nlohmann::json;

constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

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

}  // namespace objmap::eval
