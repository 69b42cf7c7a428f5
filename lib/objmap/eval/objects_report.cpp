// The object evaluation's report: its JSON and its text.
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
