#pragma once
#include <array>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "objmap/core/types.h"

// DIFF/diff.json of `objmap diff` (docs/change.md, schemas/diff.schema.json), read back: the
// registration of the after world to the before world and every object of both visits with its
// status. The one reader of it: `objmap query --diff` and `objmap report --diff`.
namespace objmap::io {

// The statuses diff.json writes, in the schema's order.
inline constexpr std::array<const char*, 7> kDiffStatuses = {
    "unchanged", "moved", "removed", "added", "changed_class", "not_seen_again", "not_seen_before"};

struct DiffRegistration {
  std::string source;  // "objects+icp" or "given"
  Pose before_from_after = Pose::Identity();
  double yaw_deg = 0.0, tilt_deg = 0.0;
  Vec3 translation_m = Vec3::Zero();
  int common_objects = 0, hypotheses = 0, icp_points = 0;
  double coarse_rms_m = 0.0, fitness = 0.0, fitness_both = 0.0, rms_m = 0.0;
  std::optional<double> sigma_translation_m, sigma_yaw_deg;  // none: not constrained
  // From the common objects' residuals; none: fewer than two common objects.
  std::optional<double> uncertainty_at_objects_m, uncertainty_yaw_deg;
};

// One object as one visit saw it.
struct DiffSide {
  int id = 0;
  std::string class_name;
  Vec3 position = Vec3::Zero();            // in that visit's world
  Vec3 position_in_before = Vec3::Zero();  // in the before world (the file's, else registered)
};

// What one visit saw of the other's object's place (lines of sight).
struct DiffEvidence {
  int views = 0, sightlines = 0, surface = 0, seen_through = 0, occluded = 0;
  double surface_share = 0.0;
};

struct DiffObject {
  std::string status;                        // one of kDiffStatuses
  std::optional<DiffSide> before, after;     // at least one; both for moved
  std::optional<double> distance_m;          // pairs only
  std::optional<Vec3> displacement_m;        // moved: after − before, before world
  std::optional<DiffEvidence> after_visit;   // what the after visit saw of the before place
  std::optional<DiffEvidence> before_visit;  // what the before visit saw of the after place
  std::string why;
  // Where it is in the before world: the before position, else the after one registered.
  const Vec3& position_in_before() const;
};

struct DiffFile {
  std::string source;  // the file read, for messages
  std::string generator, before, after, frame;
  DiffRegistration registration;
  std::map<std::string, int> counts;                  // per status
  std::vector<std::pair<std::string, int>> left_out;  // self-moving classes: (class, count)
  std::vector<DiffObject> objects;                    // in the file's order
};

// Reads and checks DIFF/diff.json (`path`: the DIFF folder or the file itself) as
// schemas/diff.schema.json says (plus: a rigid before_from_after; moved with both sides and a
// displacement; before-only statuses with a before side, after-only ones with an after side).
// Throws InputError naming the file and the bad field
// ("d/diff.json: objects[2].before.position: expected [x, y, z], got \"x\"").
DiffFile read_diff_json(const std::filesystem::path& path);

}  // namespace objmap::io
