#pragma once
#include <Eigen/Core>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "objmap/core/types.h"
#include "objmap/eval/stats.h"
#include "objmap/io/objects_json.h"

// Evaluation of an object map (the paper's Tables 3–6): object counts per class against a reference
// (Table 3), centroid errors of objects matched one-to-one by class (Tables 4–5: the map built with
// the estimated trajectory against the map built with the ground-truth trajectory, or against true
// object ground truth), precision / recall at distance thresholds, oriented-box 3D IoU, and the
// point counts of the dense and the objects-only map (Table 6).
namespace objmap::eval {

// ---- assignment
// ---------------------------------------------------------------------------------

// Minimum-cost one-to-one assignment (Hungarian / Kuhn–Munkres with potentials, O(n² m) for an
// n×m matrix, n <= m after transposing). `cost` may be rectangular; an entry that is +infinity (or
// NaN) forbids that pair. Among all assignments it first maximises the number of allowed pairs,
// then minimises their total cost. Returns, per row, the column assigned to it or -1.
std::vector<int> hungarian_assign(const Eigen::MatrixXd& cost);

// ---- oriented boxes
// -----------------------------------------------------------------------------

double obb_volume(const Obb& box);
// Exact volume of the intersection of two oriented boxes: box `a` as a convex polyhedron clipped
// by the six half-spaces of box `b` (each face polygon clipped by Sutherland–Hodgman, the cut
// closed by a cap polygon), volume as pyramids from an interior point. Relative accuracy ~1e-12.
double obb_intersection_volume(const Obb& a, const Obb& b);
// Intersection over union of the two solids, in [0, 1]; 0 when both have no volume.
double obb_iou(const Obb& a, const Obb& b);

// ---- ground-truth objects
// -----------------------------------------------------------------------

// An object that a map is compared with: a true object (objects_gt.json) or an object of the
// reference map (the map fused with the ground-truth trajectory).
struct ReferenceObject {
  int id = -1;
  std::string class_name;
  Vec3 centroid = Vec3::Zero();  // world, metres
  Obb obb;
};

// Reads ground-truth objects, detecting the format by content:
//  - JSON (first non-blank character '{'): objects_gt.json of `objmap synth`
//    (schemas/objects_gt.schema.json): objects[] with id, class, centroid, obb{center, rotation
//    (row-major 9), half_extent};
//  - text: one cuboid per data line "x y z yaw half_x half_y half_z" (metres, radians; yaw about
//    the world z axis, CubeSLAM convention; '#' comments), as fr3_cabinet's objects_gt.txt. Such
//    files carry no class: each object gets `default_class`, ids 1, 2, ... in line order, centroid
//    = the box centre.
// Throws InputError naming the file and the line or field.
std::vector<ReferenceObject> read_objects_gt(const std::filesystem::path& file,
                                             const std::string& default_class = "object");

// The objects of a map (RUN/objects.json) as reference objects (for --reference).
std::vector<ReferenceObject> to_reference(const std::vector<io::MappedObject>& objects);

// ---- the evaluation
// -----------------------------------------------------------------------------

struct ObjectEvalOptions {
  double gate_m = 0.3;  // a matched pair further apart than this (centroid distance) is unmatched
  std::vector<double> thresholds_m = {0.10, 0.25};  // precision / recall at these distances
  void check() const;                               // throws InputError naming the bad field
};

// Table 3: the number of objects of one class (or of all) in the map and in the reference.
struct CountRow {
  std::string class_name;  // "overall" for the total row
  std::size_t mapped = 0;
  std::size_t reference = 0;
  std::optional<double> error;  // |mapped − reference| / reference; none when reference == 0
};

// One pair of the one-to-one assignment (same class, centroid distance <= gate).
struct ObjectMatch {
  int map_id = -1;
  int reference_id = -1;
  std::string class_name;
  double distance_m = 0.0;          // ‖c_map − c_ref‖
  Vec3 error_xyz_m = Vec3::Zero();  // c_map − c_ref, world axes
  double iou = 0.0;                 // 3D IoU of the two oriented boxes
};

// Tables 4–5: centroid errors of the matched objects of one class (or of all).
struct ErrorRow {
  std::string class_name;  // "overall" for the total row
  std::size_t mapped = 0, reference = 0, matched = 0;
  ErrorStats distance_m;               // of the matched pairs' centroid distances
  Vec3 mean_abs_xyz_m = Vec3::Zero();  // mean |c_map − c_ref| per world axis
  ErrorStats iou;                      // of the matched pairs' 3D IoU
};

// Precision and recall with pairs matched within `threshold_m` (its own one-to-one assignment).
struct PrecisionRecall {
  double threshold_m = 0.0;
  std::size_t matched = 0;
  double precision = 0.0;  // matched / mapped objects (0 when the map is empty)
  double recall = 0.0;     // matched / reference objects (0 when the reference is empty)
};

struct ObjectEvalResult {
  std::vector<CountRow> counts;      // per class (sorted by name), then the "overall" row
  std::vector<ObjectMatch> matches;  // within the gate, sorted by reference id
  std::vector<int> unmatched_map_ids, unmatched_reference_ids;
  std::vector<ErrorRow> errors;  // per class with objects on either side, then "overall"
  std::vector<PrecisionRecall> precision_recall;  // one per options.thresholds_m
};

// Matches the map's objects to the reference's one-to-one within each class (Hungarian on the
// centroid distances, pairs over the gate forbidden) and computes the tables.
ObjectEvalResult evaluate_objects(const std::vector<io::MappedObject>& map,
                                  const std::vector<ReferenceObject>& reference,
                                  const ObjectEvalOptions& options);

// ---- Table 6
// ------------------------------------------------------------------------------------

// The "points" block of RUN/run.json (schemas/run.schema.json).
struct PointCounts {
  std::string source;  // the run.json read
  double dense_back_projected = 0, dense_map = 0, objects_raw = 0, objects_voxel_filtered = 0,
         objects_outlier_filtered = 0, semantic_map = 0, objects_map = 0;
  // 1 − objects_map / dense_map (0 when the dense map is empty): the share of points that the
  // objects-only map saves.
  double reduction() const;
};

// Throws InputError for a missing file, malformed JSON or a missing/negative key of "points".
PointCounts read_point_counts(const std::filesystem::path& run_json);

// ---- output
// -------------------------------------------------------------------------------------

struct ObjectEvalReport {
  std::string mode;  // "reference" (--reference) or "ground_truth" (--gt-objects)
  std::string map_source, reference_source;
  ObjectEvalOptions options;
  ObjectEvalResult result;
  std::optional<PointCounts> points;
};

// The JSON document of `objmap eval objects` (schemas/eval_objects.schema.json); deterministic.
std::string objects_eval_json(const ObjectEvalReport& report);
// The console tables in the paper's layout (a row per class, an overall row).
std::string objects_eval_text(const ObjectEvalReport& report);

}  // namespace objmap::eval
