#pragma once
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "objmap/core/types.h"

// The synthetic scene model: objects made of analytic primitives (boxes, capped cylinders,
// ellipsoids), ray intersection and point-to-surface distance. No rendering, no images here.
namespace objmap::sim {

enum class Shape {
  kBox,       // half_extent = half sizes along the part's x, y, z
  kCylinder,  // capped cylinder along the part's z: half_extent = (radius, radius, half height)
  kEllipsoid  // half_extent = semi-axes along x, y, z
};

// Procedural surface pattern, evaluated in the part's own frame (the texture moves with the
// object).
enum class Pattern {
  kSolid,    // base colour (with a faint grain)
  kChecker,  // 3D checker of `scale_m` cells, base/accent
  kStripes,  // stripes along the part's z, period `scale_m`
  kNoise,    // fractal value noise, feature size `scale_m`, blends base -> accent
  kKeys      // keyboard keys: accent squares of `scale_m` pitch on a base background
};

struct Material {
  Rgb base{128, 128, 128};
  Rgb accent{64, 64, 64};
  Pattern pattern = Pattern::kNoise;
  double scale_m = 0.02;  // cell, period or feature size of the pattern (metres)
  double grain = 0.06;    // amplitude of a fine value-noise grain on top (0..1), gives corners
  std::uint32_t seed = 0;
};

struct Part {
  Shape shape = Shape::kBox;
  Vec3 half_extent = Vec3::Constant(0.05);
  Pose object_from_part = Pose::Identity();
  Material material;
  // Optional, boxes only: one material per face (-x, +x, -y, +y, -z, +z) instead of `material`
  // (the room is one box seen from inside: floor, walls and ceiling).
  std::vector<Material> face_materials;
};

// The material at a surface point with outward normal `normal_in_part`.
const Material& material_at(const Part& part, const Vec3& normal_in_part);

// One object: ground truth id and class, a pose and its parts. `finalize()` fills the derived
// fields.
struct SceneObject {
  int id = 0;              // 1..N for the objects of the ground truth; 0 for structure
  std::string class_name;  // COCO name ("cup", "tv monitor", ...) or "floor", "wall", "table"
  Pose world_from_object = Pose::Identity();
  std::vector<Part> parts;

  // Derived (finalize()):
  std::vector<Pose> world_from_part;  // one per part
  Obb obb;                            // oriented box in the object's frame axes covering all parts
  Vec3 centroid = Vec3::Zero();       // centroid of the solid volume (union of the parts)
  double volume_m3 = 0.0;             // volume of the union of the parts
  Vec3 bound_center = Vec3::Zero();   // bounding sphere, for ray culling
  double bound_radius = 0.0;

  // Computes world_from_part, obb, centroid (grid integration of the union, `grid` cells along the
  // longest side), volume and the bounding sphere. Call after changing the pose or the parts.
  void finalize(int grid = 96);
};

struct Scene {
  std::vector<SceneObject> structure;  // room (floor, walls, ceiling), tables: label 0, not GT
  std::vector<SceneObject> objects;    // the ground-truth objects, ids 1..N in order
  Vec3 light_dir_world = Vec3(0.3, 0.2, 1.0).normalized();  // towards the main light
  double ambient = 0.45;                                    // share of unshaded light

  const SceneObject* find(int id) const;
};

// A ray in the world frame: point = origin + t * direction (direction need not be unit; the
// renderer uses a camera-frame direction with z = 1, so t is the depth along the optical axis).
struct Ray {
  Vec3 origin = Vec3::Zero();
  Vec3 direction = Vec3::UnitZ();
};

struct SurfaceHit {
  double t = std::numeric_limits<double>::infinity();
  const SceneObject* object = nullptr;
  int part = -1;
  Vec3 point_in_part = Vec3::Zero();
  Vec3 normal_in_part = Vec3::UnitZ();  // outward unit normal
  bool hit() const { return object != nullptr; }
};

// Nearest intersection with t in (t_min, hit->t); updates `hit` and returns true when closer.
bool intersect_part(const Part& part, const Pose& world_from_part, const Ray& ray, double t_min,
                    SurfaceHit* hit);
// The same with the ray already in the part's frame (origin `o`, direction `d`); the renderer
// transforms the camera centre once per frame and calls this.
bool intersect_part_local(const Part& part, const Vec3& o, const Vec3& d, double t_min,
                          SurfaceHit* hit);
bool intersect_object(const SceneObject& object, const Ray& ray, double t_min, SurfaceHit* hit);
// Nearest hit among the structure and the objects (t > t_min).
SurfaceHit cast_ray(const Scene& scene, const Ray& ray, double t_min = 1e-6);
// Nearest hit among `objects` (bounding spheres tested first).
SurfaceHit cast_ray(const std::vector<const SceneObject*>& objects, const Ray& ray,
                    double t_min = 1e-6);

// Unsigned distance from a point to the surface of one primitive (point in the part's frame). Exact
// for boxes and cylinders; first-order (exact on the surface and for spheres) for ellipsoids.
double distance_to_part_surface(const Part& part, const Vec3& point_in_part);
// True when the point (part frame) is inside the primitive.
bool inside_part(const Part& part, const Vec3& point_in_part);
// Distance from a world point to the nearest part surface of the object (metres). A point on the
// visible surface gives ~0; for points inside the union near an internal face it underestimates.
double distance_to_surface(const SceneObject& object, const Vec3& point_in_world);
bool inside_object(const SceneObject& object, const Vec3& point_in_world);

}  // namespace objmap::sim
