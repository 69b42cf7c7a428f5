#pragma once
#include <optional>
#include <string>
#include <vector>

#include "objmap/core/types.h"
#include "objmap/sim/scene.h"

// What holds what up in a synthetic scene, for the ground truth of gravity, support surfaces and
// `on` relations (objects_gt.json): the room's floor, every table top and every chair seat as
// horizontal rectangles, and for each object the surface or the object it rests on. Derived from
// the geometry the presets place, not from how they place it.
namespace objmap::sim {

// The scenes are built with the world's z axis up (floor at z = 0, gravity along -z).
inline Vec3 scene_up() { return Vec3::UnitZ(); }

// An object rests on a support when its lowest point is within this of the support's top (metres)
// and its centroid lies over the support (projected along up).
constexpr double kSupportToleranceM = 0.01;

// A horizontal support surface: the top face of a flat box part (the floor: the bottom face of the
// room seen from inside).
struct SupportSurface {
  int id = 0;                  // 1..S: the floor, the table tops, the seats, in scene order
  std::string label;           // "floor", "table" or "seat"
  double height_m = 0.0;       // up · (a point of the face)
  Vec3 center = Vec3::Zero();  // centre of the face, world
  std::vector<Vec3> outline;   // the face's corners in cyclic order, world
  double area_m2 = 0.0;        // of the face
  int object_id = 0;           // seats: the chair object they belong to; 0 otherwise
};

// What an object rests on: a surface (id into SceneSupport::surfaces) or another object (its id).
struct SupportRelation {
  enum class Kind { kSurface, kObject };
  Kind kind = Kind::kSurface;
  int id = 0;
  std::string label;   // the surface's label or the supporting object's class
  double gap_m = 0.0;  // object's lowest point − the support's top, metres (negative: sunk in)
};

struct SceneSupport {
  Vec3 up = scene_up();
  std::vector<SupportSurface> surfaces;
  std::vector<std::optional<SupportRelation>> on;  // one per Scene::objects, in order
};

// The surfaces of `scene` (floor, table tops, chair seats) and what each object rests on: the
// candidate (surface or other object) whose top is nearest the object's lowest point among those
// within kSupportToleranceM with the object's centroid over them; none when nothing qualifies.
SceneSupport scene_support(const Scene& scene);

// Lowest and highest point of an object along `up` (exact for its primitives).
double lowest_along(const SceneObject& object, const Vec3& up);
double highest_along(const SceneObject& object, const Vec3& up);

}  // namespace objmap::sim
