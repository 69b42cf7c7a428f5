#pragma once
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "objmap/core/types.h"
#include "objmap/sim/scene.h"

// A second visit of a synthetic scene, for `objmap diff` (docs/change.md): the same room with
// known changes (objects moved to another free place on a table, removed, added), seen from
// another start pose, in another world frame (a random yaw about up and a translation), with the
// true changes in changes_gt.json (schemas/changes_gt.schema.json).
namespace objmap::sim {

struct SecondVisitOptions {
  bool enabled = false;
  std::filesystem::path first_visit;  // the first visit's folder (for changes_gt.json)
  std::uint64_t first_seed = 1;       // the first visit's seed (its synth.json): the same scene
  int move = 1;                       // objects moved to another free place on a table
  int remove = 1;                     // objects taken away
  int add = 1;                        // objects added (copies of table-top objects' kinds)
  double min_move_m = 0.3;            // a moved object goes at least this far
  double max_shift_m = 2.0;           // the world frame's horizontal shift, at most (and ±0.3 up)
  void check() const;                 // throws InputError naming the bad field
};

// One object of either visit and what happened to it (positions: box centres, each visit's world).
struct ObjectChangeGt {
  std::string status;  // "unchanged", "moved", "removed", "added"
  int before_id = 0;   // 0: not in the first visit
  int after_id = 0;    // 0: not in the second visit
  std::string class_name;
  Vec3 before_position = Vec3::Zero();
  Vec3 after_position = Vec3::Zero();
};

struct SecondVisit {
  Pose after_from_before = Pose::Identity();  // second visit's world from the first's
  double start_angle_offset_deg = 0.0;        // the orbit starts this much further round
  std::vector<ObjectChangeGt> changes;        // first-visit objects in order, then the added
};

// The first visit's preset and seed from its synth.json (into `options`, and `preset`). Throws
// InputError naming the file or field.
void read_first_visit(const std::filesystem::path& folder, SecondVisitOptions& options,
                      std::string& preset);

// Changes `scene` (the first visit's, in its world) as `options` asks, with randomness from
// `seed`, and draws the second visit's world frame and orbit start; the scene stays in the first
// visit's world (transform_scene moves it, after the camera path is made there). Returns the
// record, after positions in the second visit's world (fewer moves or additions than asked when no
// free place is found).
SecondVisit make_second_visit(Scene& scene, const SecondVisitOptions& options, std::uint64_t seed);

// Moves every object and structure of `scene` by `after_from_before` (and the light with it).
void transform_scene(Scene& scene, const Pose& after_from_before);

// changes_gt.json text.
std::string changes_gt_json(const SecondVisit& visit, const SecondVisitOptions& options);

}  // namespace objmap::sim
