#pragma once
#include <optional>
#include <string>
#include <vector>

#include "objmap/change/visit.h"
#include "objmap/core/types.h"

// What happened to each object between two registered visits (docs/change.md, "Statuses"). The
// objects of both maps are paired in the before frame: same class at the same place (unchanged),
// another class at the same place (changed class), same class elsewhere (moved). An object left
// without a partner is judged by what the other visit saw of its place: the other visit's views
// (frustum and range of its camera at its keyframes) and its dense map along those lines of sight
// (a surface in front: occluded; the object's own surface: still there; only surfaces behind:
// seen through, the place is empty).
namespace objmap::change {

enum class Status {
  kUnchanged,     // same class, same place (or its surface is still there, undetected)
  kMoved,         // same class, another place; displacement given
  kRemoved,       // before only; the after visit saw its place empty
  kAdded,         // after only; the before visit saw its place empty
  kChangedClass,  // same place, another class
  kNotSeenAgain,  // before only; its place was out of the after visit's view: unknown
  kNotSeenBefore  // after only; its place was out of the before visit's view: unknown
};
const char* status_name(Status s);  // "unchanged", "moved", ..., "not_seen_again"

struct ClassifyOptions {
  double same_place_m = 0.15;     // paired within max(this, same_place_share · radius): same place
  double same_place_share = 0.5;  // ... of the larger object's box radius (big objects' boxes vary)
  double changed_class_size_ratio = 2.0;  // changed class: box radii within this ratio
  double max_move_m = 20.0;
  // Moved pairing: a pair's cost is its distance plus this many metres per 255 grey levels of
  // colour difference (both with colours), so that two cups of another colour are told apart.
  double colour_weight_m = 3.0;  // a same-class pair farther apart is not one object moved
  double voxel_m = 0.03;         // the other dense map's occupancy grid
  double max_range_m = 4.0;      // a view sees a place between min_range_m and this depth
  double min_range_m = 0.3;
  int image_margin_px = 4;      // ... projecting at least this far inside the image
  double behind_m = 1.5;        // seen through: a surface within this behind the point
  std::size_t max_views = 40;   // the other visit's keyframes, evenly thinned to this many
  std::size_t max_points = 60;  // an object's points tested per view, evenly thinned
  int min_sightlines = 20;      // fewer unoccluded (view, point) lines: its place not seen
  double present_share = 0.5;   // of those lines, the share ending on the object's surface
                                // from which it is still there (undetected)
  double empty_share = 0.7;     // ... passing through it, from which its place is empty (removed,
                                // added); in between: unknown (not seen again / before)
  void check() const;           // throws InputError naming the bad field
};

// What the other visit saw of one object's place: (view, point) lines of sight.
struct PlaceEvidence {
  int views = 0;         // views that had a point of it in frustum and range
  int sightlines = 0;    // unoccluded lines (view, point) that reached its place
  int surface = 0;       // ... ending on a surface at the point: something is there
  int seen_through = 0;  // ... passing the point to a surface behind it: the place is empty
  int occluded = 0;      // lines stopped by a surface in front
  double surface_share() const { return sightlines ? double(surface) / sightlines : 0.0; }
};

struct ObjectChange {
  Status status = Status::kUnchanged;
  std::optional<int> before_id, after_id;
  std::string before_class, after_class;
  std::optional<Vec3> before_position;           // before world
  std::optional<Vec3> after_position;            // after world
  std::optional<Vec3> after_position_in_before;  // the after position in the before world
  double distance_m = 0.0;           // between the two positions in the before world (pairs only)
  Vec3 displacement = Vec3::Zero();  // moved: after − before, before world
  std::optional<PlaceEvidence> evidence_after;   // the after visit about the before object's place
  std::optional<PlaceEvidence> evidence_before;  // the before visit about the after object's place
  std::string why;                               // one line
};

struct ChangeResult {
  std::vector<ObjectChange> objects;  // before objects in their order, then after-only objects
  std::vector<std::pair<std::string, int>> left_out;  // self-moving classes: (class, count)
  int count(Status s) const;
};

// Classifies every object of both visits; `before_from_after` registers them. Deterministic.
ChangeResult classify_changes(const Visit& before, const Visit& after,
                              const Pose& before_from_after, const ClassifyOptions& options);

// The evidence `viewer` holds about a place given by `points_in_viewer` (the viewer's world):
// exposed for tests.
PlaceEvidence place_evidence(const Visit& viewer, const std::vector<Vec3>& points_in_viewer,
                             const ClassifyOptions& options);

}  // namespace objmap::change
