#pragma once
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "objmap/core/types.h"

// The scene around the objects: which way is up, the horizontal surfaces things stand on (floor,
// table tops, seats) and how the objects relate to them and to each other (`on`, `near`, `above`,
// `under`). What a robot told "bring me the cup on the table" needs besides the objects' positions.
// All in the trajectory's world frame, which need not be z-up (ORB-SLAM2 writes its trajectories in
// the first camera's frame). docs/scene.md describes the method and its thresholds.
namespace objmap::scene {

// ---- Up direction --------------------------------------------------------------------------

struct UpOptions {
  // "auto": estimated from the cameras and the dense map's planes; "x", "-y", "z", ...: a world
  // axis; "x,y,z": a given vector (normalised).
  std::string mode = "auto";
  double sample_voxel_m = 0.04;        // the dense map is sampled on this grid (the cameras' frame)
  double max_prior_angle_deg = 70.0;   // a normal this close to the cameras' up may be horizontal
  double max_view_elevation = 0.25;    // ... when the cameras do not look up at it (mean sin)
  double density_cell_deg = 2.0;       // the normals' density: cells of this size, 5 × 5 summed
  double family_deg = 10.0;            // up: the mean of the normals this close to it (mean shift)
  double min_plane_share = 0.02;       // ... which hold at least this share of the sample
  double plane_distance_m = 0.02;      // levels along up (floor, table tops): split at gaps ...
  int max_planes = 8;                  // ... at most this many, largest first
  double parallel_deg = 5.0;           // up: the mean of the levels' planes this close to it
  double disagree_warning_deg = 45.0;  // planes vs cameras beyond this: a warning
  void check() const;                  // throws InputError naming the field
};

// One horizontal level of the dense map (a floor, a table top), as evidence for the up direction.
struct PlaneEvidence {
  Vec3 normal = Vec3::UnitZ();  // unit, its points' own plane (least squares), signed toward up
  double offset = 0.0;          // normal · p for the plane's points
  std::size_t inliers = 0;      // sample points
  double angle_to_prior_deg = 0.0;
  double view_elevation = 0.0;  // mean of the cameras' viewing directions · normal
  bool used = false;            // its points' normals are among those up is the mean of
};

struct UpEstimate {
  Vec3 up = Vec3::UnitZ();                                           // unit, world frame
  Eigen::Matrix3d gravity_from_world = Eigen::Matrix3d::Identity();  // R · up = +z
  std::string source;  // "given", "planes" or "cameras"
  Vec3 camera_prior = Vec3::UnitZ();
  Vec3 camera_view = Vec3::UnitX();  // mean of the cameras' viewing directions (z axes)
  double camera_agreement = 0.0;     // |mean of the cameras' up axes| in [0, 1]
  double prior_to_up_deg = 0.0;      // angle between the cameras' prior and the result
  std::size_t sample_points = 0;     // points of the sampled dense map
  std::vector<PlaneEvidence> planes;
  std::vector<std::string> warnings;  // evidence that disagrees, said in one line each
};

// Parses UpOptions::mode; nullopt for "auto". Throws InputError(where, ...) for anything else.
std::optional<Vec3> parse_up(const std::string& text, const std::string& where);

// The rotation taking `up` (unit) to +z by the shortest arc (identity for +z, a half turn about x
// for -z).
Eigen::Matrix3d gravity_from_world(const Vec3& up);

// The up direction of the world: given, or estimated from the cameras' poses (world_from_cam;
// cameras are held roughly upright: their y axis points down) refined by the dominant horizontal
// planes of `map_points` (floor, table tops).
UpEstimate estimate_up(const std::vector<Pose>& cameras, const std::vector<Vec3f>& map_points,
                       const UpOptions& options);

// ---- Support surfaces ----------------------------------------------------------------------

struct SurfaceOptions {
  bool enabled = true;
  double sample_voxel_m = 0.04;     // the dense map is sampled on this grid
  double max_tilt_deg = 25.0;       // a point is horizontal when its normal is this close to up
  double cluster_gap_m = 0.06;      // Euclidean clustering of the horizontal points into patches
  double min_area_m2 = 0.03;        // smaller patches are not surfaces
  double min_width_m = 0.03;        // a patch's narrower spread (std): not the slice of a wall
  double merge_height_m = 0.12;     // layers of one surface (depth noise) within this height merge
  double merge_gap_m = 0.3;         // pieces at one level this close merge (cut by objects on it)
  double piece_height_m = 0.06;     // ... "one level": medians this close (a tilted floor)
  double floor_min_area_m2 = 0.3;   // the floor: the lowest patch of at least this area
  double table_min_height_m = 0.4;  // a table top: this far above the floor ...
  double table_max_height_m = 1.2;  // ... and at most this far
  double table_min_area_m2 = 0.1;
  double table_max_area_m2 = 6.0;  // larger patches are no table (a floor seen without chairs)
  void check() const;
};

struct Surface {
  int id = 0;           // 1.. in descending area
  std::string label;    // "floor", "table", "seat" or "surface"
  double height_m = 0;  // up · p of its points (mean)
  Vec3 center = Vec3::Zero();
  double area_m2 = 0.0;       // occupied cells of the sample grid × cell area
  std::vector<Vec3> outline;  // convex hull at height_m, counter-clockwise seen from above
  std::size_t points = 0;     // sample points
  std::optional<int> object;  // the object whose top it is (a seat, a shelf's board)
  std::string label_rule;     // why it has its label
};

// ---- Objects and relations -----------------------------------------------------------------

// What the relations need of an object: its id, class and filtered points.
struct SceneObject {
  int id = 0;
  std::string class_name;
  Vec3 position = Vec3::Zero();
  const PointCloud* cloud = nullptr;
};

struct RelationOptions {
  double on_below_m = 0.06;  // an object's bottom may lie this far below its support's top ...
  double on_above_m = 0.08;  // ... or this far above it (its lowest part hidden from the camera)
  double outline_margin_m = 0.03;  // footprint centre inside the support's outline, this margin
  double min_footprint_overlap = 0.25;  // ... or this share of the footprint over the outline
  // `near`: the clearance between the two objects (their footprints' gap seen from above and the
  // gap between their height ranges, 0 when they touch or overlap) is at most
  // clamp(near_scale × the smaller object's largest horizontal extent, near_min_m, near_max_m):
  // a chair pulled up to a dining table (0.5 m chair: within 0.5 m), a cup 30 cm from a laptop
  // (within the floor 0.4 m), not a cup 1 m from a fridge. docs/scene.md, "Relations".
  double near_scale = 1.0;       // times the smaller object's size
  double near_min_m = 0.4;       // at least this: a small thing is near what is a hand's reach away
  double near_max_m = 1.0;       // at most this: a sofa is not near what stands 2 m from it
  bool near_by_centres = false;  // the old rule: box centres within near_radius_m
  double near_radius_m = 0.5;    // ... that rule's radius (only with near_by_centres)
  double stack_tolerance_m = 0.03;      // `above`: bottom at least top − this
  double support_min_area_ratio = 0.5;  // an object support's top ≥ this × the object's footprint
  double top_band_m = 0.05;  // an object's top: its points this close below its top height
  // Furniture, and what stands on nothing, stands on the floor (any piece seen in the room) when
  // its bottom is at most this above the floor's height.
  double floor_gap_m = 0.15;
  // Furniture stands on the floor also when its bottom is up to this above it: its legs or base
  // hidden (seen from above over a table, under a desk); gap_m then says how much is hidden.
  double hidden_base_m = 1.0;
  // A table top holds under what hides it: an object on nothing at a table's height whose
  // footprint comes within this of the table's seen outline stands on it (the outline is sampled
  // on 4 cm cells and ends where the object hides the top).
  double hidden_reach_m = 0.1;
  // Two objects of one class whose boxes interpenetrate by this share of the smaller box (the
  // footprints' overlap share × the height ranges' overlap share) are a suspected duplicate: one
  // physical object seen as two, neither on the other.
  double duplicate_overlap = 0.3;
  void check() const;
};

struct Support {
  std::string kind;  // "surface" or "object"
  int id = 0;
  std::string label;   // the surface's label or the object's class
  double gap_m = 0.0;  // object's bottom − support's top (negative: slightly into it)
};

struct Neighbour {
  int id = 0;
  // near: the clearance between the two (0 when they touch; box centres with near_by_centres);
  // above/under: the vertical gap.
  double distance_m = 0.0;
};

// Another object of the same class that interpenetrates this one (RelationOptions::
// duplicate_overlap): likely the same physical object.
struct SuspectedDuplicate {
  int id = 0;
  double overlap = 0.0;  // share of the smaller box, in [0, 1]
};

struct Relations {
  std::optional<Support> on;
  std::vector<SuspectedDuplicate> duplicates;  // ascending id
  std::vector<Neighbour> near;                 // objects, nearest first
  std::vector<Neighbour> near_surfaces;        // surfaces (id), nearest first (same rule)
  std::vector<Neighbour> above;  // objects this one is above (gap = its bottom − their top)
  std::vector<Neighbour> under;  // objects above this one
};

struct SceneOptions {
  UpOptions up;
  SurfaceOptions surfaces;
  RelationOptions relations;
  void check() const;
};

struct SceneGraph {
  UpEstimate up;
  std::vector<Surface> surfaces;
  std::vector<Relations> relations;  // one per object, in the order given
  double seconds_up = 0.0, seconds_surfaces = 0.0, seconds_relations = 0.0;
};

// The up direction, then the surfaces on it, as estimate_up and find_surfaces give them (the same
// results) in less time: the map is sampled once when both use the same grid, and the sample's
// normals are computed on a second thread while RANSAC looks for the up's planes. Fills graph.up,
// graph.surfaces and their seconds (the sample counts to the up's).
void find_up_and_surfaces(const std::vector<Pose>& cameras, const std::vector<Vec3f>& map_points,
                          const SceneOptions& options, SceneGraph& graph);

// What find_up_and_surfaces reads of the dense map, taken where the map is at hand, so that the map
// may change or go before the step runs (objmap follow): its sample on the cameras' grid when the
// up and the surfaces share one (the defaults), else a copy of its points. Cheap to copy.
class SceneSample {
 public:
  SceneSample(const std::vector<Pose>& cameras, const std::vector<Vec3f>& map_points,
              const SceneOptions& options);
  struct Taken;  // up_and_surfaces.cpp

 private:
  std::shared_ptr<const Taken> taken_;
  friend void find_up_and_surfaces(const SceneSample& sample, const SceneOptions& options,
                                   SceneGraph& graph);
};
// find_up_and_surfaces on a sample taken with the same options: the same results (the sample's
// time counts to the up's).
void find_up_and_surfaces(const SceneSample& sample, const SceneOptions& options,
                          SceneGraph& graph);

// Surfaces of the map given the up direction (ids 1.. by area, labelled "surface"): the map alone,
// so that it can run beside the objects' filtering.
std::vector<Surface> find_surfaces(const std::vector<Vec3f>& map_points, const Vec3& up,
                                   const SurfaceOptions& options);
// Which surface is an object's top (a chair's seat, a shelf's board): Surface::object.
void mark_object_tops(std::vector<Surface>& surfaces, const Vec3& up,
                      const std::vector<SceneObject>& objects);

// The relations of every object, then the surfaces' labels (the table is what small objects stand
// on when the floor is not seen), which the `on` supports then carry.
std::vector<Relations> relate_objects(const std::vector<SceneObject>& objects,
                                      std::vector<Surface>& surfaces, const Vec3& up,
                                      const SurfaceOptions& surface_options,
                                      const RelationOptions& options);

}  // namespace objmap::scene
