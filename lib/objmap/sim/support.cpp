#include "objmap/sim/support.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "objmap/core/polygon.h"

namespace objmap::sim {

namespace {

// Half the extent of a part along the unit vector `u` (world), about its centre.
double half_extent_along(const Part& part, const Pose& world_from_part, const Vec3& u) {
  const Eigen::Matrix3d& r = world_from_part.linear();
  const Vec3 c(r.col(0).dot(u), r.col(1).dot(u), r.col(2).dot(u));  // u in the part's axes
  const Vec3& h = part.half_extent;
  switch (part.shape) {
    case Shape::kBox:
      return c.cwiseAbs().dot(h);
    case Shape::kCylinder:
      return std::abs(c.z()) * h.z() + h.x() * std::sqrt(std::max(0.0, 1.0 - c.z() * c.z()));
    case Shape::kEllipsoid:
      return c.cwiseProduct(h).norm();
  }
  return 0.0;
}

// A box part lying flat: its z axis along up and its top face wider than the box is thick.
bool flat_horizontal_box(const Part& part, const Pose& world_from_part, const Vec3& up) {
  if (part.shape != Shape::kBox) return false;
  const Vec3 z = world_from_part.linear().col(2);
  const Vec3& h = part.half_extent;
  return std::abs(z.dot(up)) > 1.0 - 1e-9 && std::min(h.x(), h.y()) > h.z();
}

// The face of a box part at part-frame z = `z_side` * half height, as a surface.
SupportSurface box_face(const Part& part, const Pose& world_from_part, double z_side,
                        const Vec3& up) {
  const Vec3& h = part.half_extent;
  const double sx[4] = {-1, 1, 1, -1}, sy[4] = {-1, -1, 1, 1};
  SupportSurface s;
  s.outline.resize(4);
  for (int k = 0; k < 4; ++k)
    s.outline[k] = world_from_part * Vec3(sx[k] * h.x(), sy[k] * h.y(), z_side * h.z());
  s.center = world_from_part * Vec3(0, 0, z_side * h.z());
  s.height_m = up.dot(s.center);
  s.area_m2 = 4.0 * h.x() * h.y();
  return s;
}

// True when the vertical line through `point` meets the box (slab test).
bool over_box(const Vec3& point, const Obb& box, const Vec3& up) {
  double t_min = -std::numeric_limits<double>::infinity();
  double t_max = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    const Vec3 axis = box.rotation.col(k);
    const double offset = axis.dot(point - box.center), rate = axis.dot(up);
    const double h = box.half_extent[k];
    if (std::abs(rate) < 1e-12) {
      if (std::abs(offset) > h) return false;
      continue;
    }
    const double t0 = (-h - offset) / rate, t1 = (h - offset) / rate;
    t_min = std::max(t_min, std::min(t0, t1));
    t_max = std::min(t_max, std::max(t0, t1));
  }
  return t_min <= t_max;
}

void add_surfaces(std::vector<SupportSurface>* out, const SceneObject& o, const char* label,
                  double z_side, const Vec3& up) {
  for (std::size_t p = 0; p < o.parts.size(); ++p) {
    const Part& part = o.parts[p];
    const Pose& world_from_part = o.world_from_part[p];
    const bool room_floor = z_side < 0 && part.shape == Shape::kBox;
    if (!room_floor && !flat_horizontal_box(part, world_from_part, up)) continue;
    SupportSurface s = box_face(part, world_from_part, z_side, up);
    s.label = label;
    s.object_id = o.id;
    out->push_back(s);
  }
}

std::vector<SupportSurface> find_surfaces(const Scene& scene, const Vec3& up) {
  std::vector<SupportSurface> surfaces;
  for (const SceneObject& o : scene.structure)
    if (o.class_name == "room") add_surfaces(&surfaces, o, "floor", -1.0, up);
  for (const SceneObject& o : scene.structure)
    if (o.class_name == "table") add_surfaces(&surfaces, o, "table", 1.0, up);
  for (const SceneObject& o : scene.objects)
    if (o.class_name == "chair") add_surfaces(&surfaces, o, "seat", 1.0, up);
  for (std::size_t i = 0; i < surfaces.size(); ++i) {
    surfaces[i].id = static_cast<int>(i) + 1;
    if (surfaces[i].label != "seat") surfaces[i].object_id = 0;  // structure has no object id
  }
  return surfaces;
}

// Keeps `candidate` in `best` when it qualifies and is nearer than what `best` holds.
void consider(std::optional<SupportRelation>* best, const SupportRelation& candidate) {
  if (std::abs(candidate.gap_m) > kSupportToleranceM) return;
  if (!*best || std::abs(candidate.gap_m) < std::abs((*best)->gap_m)) *best = candidate;
}

std::optional<SupportRelation> support_of(const SceneObject& o, const Scene& scene,
                                          const std::vector<SupportSurface>& surfaces,
                                          const Vec3& up) {
  const double lowest = lowest_along(o, up);
  std::optional<SupportRelation> best;
  for (const SupportSurface& s : surfaces)
    if (s.object_id != o.id && projects_into_polygon(o.centroid, s.outline, up))
      consider(&best, {SupportRelation::Kind::kSurface, s.id, s.label, lowest - s.height_m});
  for (const SceneObject& other : scene.objects)
    if (other.id != o.id && over_box(o.centroid, other.obb, up))
      consider(&best, {SupportRelation::Kind::kObject, other.id, other.class_name,
                       lowest - highest_along(other, up)});
  return best;
}

}  // namespace

double lowest_along(const SceneObject& object, const Vec3& up) {
  double lowest = std::numeric_limits<double>::infinity();
  for (std::size_t p = 0; p < object.parts.size(); ++p)
    lowest =
        std::min(lowest, up.dot(object.world_from_part[p].translation()) -
                             half_extent_along(object.parts[p], object.world_from_part[p], up));
  return lowest;
}

double highest_along(const SceneObject& object, const Vec3& up) {
  double highest = -std::numeric_limits<double>::infinity();
  for (std::size_t p = 0; p < object.parts.size(); ++p)
    highest =
        std::max(highest, up.dot(object.world_from_part[p].translation()) +
                              half_extent_along(object.parts[p], object.world_from_part[p], up));
  return highest;
}

SceneSupport scene_support(const Scene& scene) {
  SceneSupport support;
  support.surfaces = find_surfaces(scene, support.up);
  for (const SceneObject& o : scene.objects)
    support.on.push_back(support_of(o, scene, support.surfaces, support.up));
  return support;
}

}  // namespace objmap::sim
