#pragma once
#include <Eigen/Core>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "objmap/core/types.h"
#include "objmap/eval/ate.h"
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
  // Where the object is: the box centre of a true object (obb.center; a position list's position),
  // a reference map's `position`.
  Vec3 position = Vec3::Zero();
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

// One pair of the one-to-one assignment (same canonical class; within the gate, or beyond it for
// the objects left over).
struct ObjectMatch {
  int map_id = -1;
  int reference_id = -1;
  std::string class_name;
  double distance_m = 0.0;          // ‖c_map − c_ref‖
  Vec3 error_xyz_m = Vec3::Zero();  // c_map − c_ref, world axes
  double iou = 0.0;                 // 3D IoU of the two oriented boxes
  // ‖p_map − p_ref‖: the map object's `position` to the reference's (a true object's box centre).
  double position_distance_m = 0.0;
};

// Tables 4–5: centroid errors of the matched objects of one class (or of all).
// Every reference object of the row is matched (within the gate), beyond the gate or missed:
// matched + beyond_gate + missed = reference; every map object not matched within the gate is a
// false positive: matched + false_positives = mapped.
struct ErrorRow {
  std::string class_name;  // "overall" for the total row
  std::size_t mapped = 0, reference = 0, matched = 0;
  std::size_t beyond_gate = 0, missed = 0, false_positives = 0;
  ErrorStats distance_m;               // of the matched pairs' centroid distances
  Vec3 mean_abs_xyz_m = Vec3::Zero();  // mean |c_map − c_ref| per world axis
  ErrorStats iou;                      // of the matched pairs' 3D IoU
  ErrorStats position_distance_m;      // of the matched pairs' position distances
  // Over every reference object (count = reference): a matched or beyond-gate object at its
  // distance, a missed one at the gate; so a gate never hides a bad object.
  ErrorStats distance_all_m;
  ErrorStats iou_all;  // over every reference object, a missed one at 0
};

// Precision and recall with pairs matched within `threshold_m` (its own one-to-one assignment).
struct PrecisionRecall {
  double threshold_m = 0.0;
  std::size_t matched = 0;
  double precision = 0.0;  // matched / mapped objects (0 when the map is empty)
  double recall = 0.0;     // matched / reference objects (0 when the reference is empty)
};

// What became of one reference object.
struct ReferenceOutcome {
  int reference_id = -1;
  std::string class_name;            // canonical
  std::string status;                // "matched" (within the gate), "beyond_gate" or "missed"
  std::optional<ObjectMatch> match;  // its pair; none when missed
};

struct ObjectEvalResult {
  std::vector<CountRow> counts;      // per class (sorted by name), then the "overall" row
  std::vector<ObjectMatch> matches;  // within the gate, sorted by reference id
  // The reference and map objects left over, paired one-to-one by class without a gate (nearest
  // first, Hungarian): each pair is further apart than the gate. Sorted by reference id.
  std::vector<ObjectMatch> beyond_gate;
  // unmatched_map_ids: every map object not matched within the gate, the false positives (those
  // paired beyond the gate included); unmatched_reference_ids: every reference object not matched
  // within the gate; missed_reference_ids: those of them without a pair beyond the gate either.
  std::vector<int> unmatched_map_ids, unmatched_reference_ids, missed_reference_ids;
  std::vector<ReferenceOutcome> reference_objects;  // every reference object, sorted by id
  std::vector<ErrorRow> errors;  // per class with objects on either side, then "overall"
  std::vector<PrecisionRecall> precision_recall;  // one per options.thresholds_m
};

// One-to-one pairs (map index, reference index) of the same canonical class
// (segmentation::canonical_class: "tvmonitor" = "tv monitor" = "tv_monitor") whose centroids are
// at most `gate_m` apart: per class, the Hungarian assignment on the centroid distances with the
// pairs over the gate forbidden (the most pairs, then the least total distance). Sorted by map
// index. `gate_m` = infinity pairs every object it can.
std::vector<std::pair<std::size_t, std::size_t>> match_by_class(
    const std::vector<io::MappedObject>& map, const std::vector<ReferenceObject>& reference,
    double gate_m);

// Matches the map's objects to the reference's (match_by_class within the gate, then the objects
// left over without a gate: beyond_gate) and computes the tables. Class names are compared and
// reported canonically.
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
  // The paper's Table 6 figure (its 45.3–61.5%): 1 − objects_map / dense_map (0 when the dense
  // map is empty), the share of points that the objects-only map saves.
  double reduction() const;
  // Eq 18's own reduction: 1 − objects_outlier_filtered / objects_voxel_filtered (0 when no
  // voxel-filtered points), the share of the object points that the outlier filter removes.
  double reduction_eq18() const;
};

// Throws InputError for a missing file, malformed JSON or a missing/negative key of "points".
PointCounts read_point_counts(const std::filesystem::path& run_json);

// ---- alignment (--align)
// ------------------------------------------------------------------------

// A map whose frame differs from the reference's is moved into it by a rigid transform before it is
// evaluated; how that transform was found is part of the report.
struct ObjectAlignment {
  std::string method = "none";    // "none", "trajectory" or "objects"
  Similarity reference_from_map;  // scale 1
  std::size_t pairs = 0;          // camera positions (trajectory) or objects (objects) aligned
  double rmse_m = 0.0;            // of those pairs after the alignment
  std::string gt_trajectory, trajectory;  // method "trajectory": the two files
};

// The objects with centroid, oriented box and axis-aligned box (the box around the moved AABB)
// moved by `transform` (its scale applies to the box extents).
std::vector<io::MappedObject> transform_objects(const std::vector<io::MappedObject>& objects,
                                                const Similarity& transform);

// SE(3) of eval ate (associate.py's stamps, Umeyama without scale) from the trajectory the map was
// fused with (`est`, the map's frame) to the ground truth's (the reference's frame). Throws
// InputError as evaluate_ate.
ObjectAlignment align_by_trajectories(const Trajectory& gt, const Trajectory& est);

// SE(3) from the objects themselves (docs/cli.md, "eval objects --align objects"):
//  1. hypotheses: the identity, and Umeyama on every triple of same-class (map, reference) pairs
//     whose three map-side distances agree with the reference-side ones within 2 gates (the
//     first kMaxAlignHypotheses of them, in index order);
//  2. the hypothesis under which the most reference objects have a same-class map object within
//     the gate wins (ties: the smaller sum of those distances);
//  3. refinement: match_by_class within the gate, Umeyama on the pairs, until the pairs repeat
//     (at most 20 rounds).
// Throws InputError("--align objects", ...) when fewer than 3 objects match in the end.
ObjectAlignment align_by_objects(const std::vector<io::MappedObject>& map,
                                 const std::vector<ReferenceObject>& reference, double gate_m);
constexpr std::size_t kMaxAlignHypotheses = 200000;

// ---- output
// -------------------------------------------------------------------------------------

struct ObjectEvalReport {
  std::string mode;  // "reference" (--reference) or "ground_truth" (--gt-objects)
  std::string map_source, reference_source;
  ObjectEvalOptions options;
  ObjectAlignment alignment;  // how the map was brought into the reference's frame
  ObjectEvalResult result;
  std::optional<PointCounts> points;
};

// The JSON document of `objmap eval objects` (schemas/eval_objects.schema.json); deterministic.
std::string objects_eval_json(const ObjectEvalReport& report);
// The console tables in the paper's layout (a row per class, an overall row).
std::string objects_eval_text(const ObjectEvalReport& report);

}  // namespace objmap::eval
