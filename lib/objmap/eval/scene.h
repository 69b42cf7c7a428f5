#pragma once
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "objmap/core/types.h"
#include "objmap/eval/ate.h"
#include "objmap/eval/objects.h"
#include "objmap/eval/stats.h"
#include "objmap/io/objects_json.h"
#include "objmap/io/scene_json.h"

// Evaluation of the scene structure of an object map against the ground truth of `objmap synth`
// (docs/scene.md): the up direction of the world, the horizontal support surfaces (floor, table
// tops, seats) and each object's `on` relation. The map's objects are matched to the true ones as
// `eval objects` matches them (evaluate_objects).
namespace objmap::eval {

// The scene of a map (objects.json) or of the ground truth (objects_gt.json): io/scene_json.h
// reads both (io::read_map_scene, io::read_gt_scene).
using SceneDescription = io::SceneDescription;
using SceneSurface = io::SceneSurface;
using OnRelation = io::SceneRelation;

// Maps a map's scene from its frame into another by `target_from_source`: points, directions,
// surface heights (h' = s·h + up'·t), outlines, the objects' positions and the relations' figures
// (objects' boxes: eval::transform_objects, objects.h).
SceneDescription transform_scene(const SceneDescription& scene,
                                 const Similarity& target_from_source);

// A true surface and the map surface matched to it: the map surface whose centre lies inside the
// true outline (projected along the true up), with the true label if one such has it, else any;
// the nearest centre among several; each map surface matched at most once (floor/table matches
// with the true label are made first).
struct SurfaceMatch {
  int gt_id = 0;
  std::string gt_label;
  double gt_height_m = 0.0;
  std::optional<int> map_id;  // none: missed
  std::string map_label;
  double map_height_m = 0.0;
  double height_error_m = 0.0;  // map − true (0 when missed)
  bool same_label = false;
};

// `on` of one matched pair of objects.
struct RelationCheck {
  int gt_id = 0, map_id = 0;
  std::string class_name;
  std::optional<OnRelation> gt_on, map_on;
  bool correct = false;  // both present and the map's target is the true one's
};

struct RelationScores {
  std::size_t predicted = 0;  // matched map objects with an `on`
  std::size_t relevant = 0;   // matched true objects with an `on`
  std::size_t correct = 0;
  double precision = 0.0;  // correct / predicted (0 when none predicted)
  double recall = 0.0;     // correct / relevant (0 when none relevant)
  std::size_t unmatched_map_with_on = 0, unmatched_gt_with_on = 0;  // outside the scores
};

struct SceneEvalResult {
  double up_angle_deg = 0.0;
  std::vector<SurfaceMatch> surfaces;    // one per true surface, in its order
  std::size_t found = 0, missed = 0;     // of the true floor and table surfaces
  ErrorStats height_abs_error_m;         // |height error| of the found floor and table surfaces
  std::vector<RelationCheck> relations;  // one per matched object pair, by true id
  RelationScores on;
};

// Everything in the ground truth's frame. `options` as for evaluate_objects (its matching).
SceneEvalResult evaluate_scene(const std::vector<io::MappedObject>& map_objects,
                               const SceneDescription& map_scene,
                               const std::vector<ReferenceObject>& gt_objects,
                               const SceneDescription& gt_scene, const ObjectEvalOptions& options);

// The SE(3) that brought the map into the ground truth's frame: evaluate_ate of the run's
// trajectory against the ground-truth trajectory.
struct SceneAlignment {
  std::string gt_trajectory, trajectory;  // the files
  Similarity gt_from_map;
  ErrorStats ate_m;  // the trajectory's ATE after that alignment
};

struct SceneEvalReport {
  std::string map_source, gt_source;
  ObjectEvalOptions options;
  std::optional<SceneAlignment> alignment;  // none: the map is in the ground truth's frame
  SceneEvalResult result;
};

// The JSON document of `objmap eval scene` (schemas/eval_scene.schema.json); deterministic.
std::string scene_eval_json(const SceneEvalReport& report);
std::string scene_eval_text(const SceneEvalReport& report);

}  // namespace objmap::eval
