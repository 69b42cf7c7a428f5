#include "objmap/sim/scene.h"

#include <algorithm>
#include <cmath>

namespace objmap::sim {

namespace {

// Half-width of a primitive along the unit direction `w` given in the part's frame (support
// function).
double support(const Part& part, const Vec3& w) {
  const Vec3& h = part.half_extent;
  switch (part.shape) {
    case Shape::kBox:
      return std::abs(w.x()) * h.x() + std::abs(w.y()) * h.y() + std::abs(w.z()) * h.z();
    case Shape::kCylinder:
      return h.x() * std::sqrt(std::max(0.0, w.x() * w.x() + w.y() * w.y())) +
             h.z() * std::abs(w.z());
    case Shape::kEllipsoid:
      return w.cwiseProduct(h).norm();
  }
  return 0.0;
}

// Smallest root of a t^2 + b t + c = 0 with t in (t_min, t_max); false when none.
bool smallest_root(double a, double b, double c, double t_min, double t_max, double* t,
                   double* t_other = nullptr) {
  if (std::abs(a) < 1e-300) return false;
  const double disc = b * b - 4.0 * a * c;
  if (disc < 0.0) return false;
  const double s = std::sqrt(disc);
  // Numerically stable pair of roots.
  const double q = -0.5 * (b + (b >= 0.0 ? s : -s));
  double r1 = q / a;
  double r2 = q != 0.0 ? c / q : r1;
  if (r1 > r2) std::swap(r1, r2);
  if (t_other) *t_other = r2;
  if (r1 > t_min && r1 < t_max) {
    *t = r1;
    return true;
  }
  if (r2 > t_min && r2 < t_max) {
    *t = r2;
    return true;
  }
  return false;
}

}  // namespace

const SceneObject* Scene::find(int id) const {
  for (const auto& o : objects)
    if (o.id == id) return &o;
  return nullptr;
}

void SceneObject::finalize(int grid) {
  world_from_part.clear();
  for (const auto& p : parts) world_from_part.push_back(world_from_object * p.object_from_part);

  // Tight box in the object's axes: support function of each part along the object axes.
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = -lo;
  for (const auto& p : parts) {
    const Eigen::Matrix3d part_from_object_r = p.object_from_part.linear().transpose();
    const Vec3 c = p.object_from_part.translation();
    for (int k = 0; k < 3; ++k) {
      const double r = support(p, part_from_object_r.col(k));
      lo[k] = std::min(lo[k], c[k] - r);
      hi[k] = std::max(hi[k], c[k] + r);
    }
  }
  const Vec3 center_in_object = 0.5 * (lo + hi);
  obb.center = world_from_object * center_in_object;
  obb.rotation = world_from_object.linear();
  obb.half_extent = 0.5 * (hi - lo);
  bound_center = obb.center;
  bound_radius = obb.half_extent.norm() + 1e-6;

  // Centroid and volume of the union of the parts: midpoint rule on a regular grid in the box.
  const Vec3 size = hi - lo;
  const double cell = size.maxCoeff() / std::max(grid, 1);
  const int nx = std::max(1, static_cast<int>(std::ceil(size.x() / cell)));
  const int ny = std::max(1, static_cast<int>(std::ceil(size.y() / cell)));
  const int nz = std::max(1, static_cast<int>(std::ceil(size.z() / cell)));
  const Vec3 step(size.x() / nx, size.y() / ny, size.z() / nz);
  std::vector<Pose> part_from_object;
  for (const auto& p : parts) part_from_object.push_back(p.object_from_part.inverse());
  Vec3 sum = Vec3::Zero();
  long long count = 0;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      for (int k = 0; k < nz; ++k) {
        const Vec3 q = lo + Vec3((i + 0.5) * step.x(), (j + 0.5) * step.y(), (k + 0.5) * step.z());
        for (std::size_t pi = 0; pi < parts.size(); ++pi) {
          if (inside_part(parts[pi], part_from_object[pi] * q)) {
            sum += q;
            ++count;
            break;
          }
        }
      }
  const Vec3 centroid_in_object =
      count > 0 ? Vec3(sum / static_cast<double>(count)) : center_in_object;
  centroid = world_from_object * centroid_in_object;
  volume_m3 = static_cast<double>(count) * step.x() * step.y() * step.z();
}

bool intersect_part(const Part& part, const Pose& world_from_part, const Ray& ray, double t_min,
                    SurfaceHit* hit) {
  const Eigen::Matrix3d part_from_world_r = world_from_part.linear().transpose();
  const Vec3 o = part_from_world_r * (ray.origin - world_from_part.translation());
  const Vec3 d = part_from_world_r * ray.direction;
  return intersect_part_local(part, o, d, t_min, hit);
}

bool intersect_part_local(const Part& part, const Vec3& o, const Vec3& d, double t_min,
                          SurfaceHit* hit) {
  const Vec3& h = part.half_extent;
  double best = hit->t;
  Vec3 normal = Vec3::UnitZ();
  bool found = false;

  switch (part.shape) {
    case Shape::kBox: {
      double t_near = -std::numeric_limits<double>::infinity();
      double t_far = std::numeric_limits<double>::infinity();
      int axis_near = 0, axis_far = 0;
      for (int k = 0; k < 3; ++k) {
        if (std::abs(d[k]) < 1e-300) {
          if (std::abs(o[k]) > h[k]) return false;
          continue;
        }
        double t1 = (-h[k] - o[k]) / d[k];
        double t2 = (h[k] - o[k]) / d[k];
        if (t1 > t2) std::swap(t1, t2);
        if (t1 > t_near) {
          t_near = t1;
          axis_near = k;
        }
        if (t2 < t_far) {
          t_far = t2;
          axis_far = k;
        }
      }
      if (t_near > t_far) return false;
      if (t_near > t_min && t_near < best) {
        best = t_near;
        normal = Vec3::Zero();
        normal[axis_near] = d[axis_near] > 0 ? -1.0 : 1.0;
        found = true;
      } else if (t_near <= t_min && t_far > t_min && t_far < best) {  // ray starts inside
        best = t_far;
        normal = Vec3::Zero();
        normal[axis_far] = d[axis_far] > 0 ? 1.0 : -1.0;
        found = true;
      }
      break;
    }
    case Shape::kCylinder: {
      const double r = h.x();
      double t = 0.0;
      // Side: (ox + t dx)^2 + (oy + t dy)^2 = r^2, with |z| <= half height.
      const double a = d.x() * d.x() + d.y() * d.y();
      const double b = 2.0 * (o.x() * d.x() + o.y() * d.y());
      const double c = o.x() * o.x() + o.y() * o.y() - r * r;
      double t_other = 0.0;
      if (smallest_root(a, b, c, t_min, best, &t, &t_other)) {
        const Vec3 p = o + t * d;
        if (std::abs(p.z()) <= h.z()) {
          best = t;
          normal = Vec3(p.x(), p.y(), 0.0).normalized();
          found = true;
        } else if (t_other > t &&
                   t_other < best) {  // first root outside the height: try the second
          const Vec3 p2 = o + t_other * d;
          if (std::abs(p2.z()) <= h.z()) {
            best = t_other;
            normal = Vec3(p2.x(), p2.y(), 0.0).normalized();
            found = true;
          }
        }
      }
      // Caps.
      if (std::abs(d.z()) > 1e-300) {
        for (double s : {-1.0, 1.0}) {
          const double tc = (s * h.z() - o.z()) / d.z();
          if (tc > t_min && tc < best) {
            const Vec3 p = o + tc * d;
            if (p.x() * p.x() + p.y() * p.y() <= r * r) {
              best = tc;
              normal = Vec3(0.0, 0.0, s);
              found = true;
            }
          }
        }
      }
      break;
    }
    case Shape::kEllipsoid: {
      const Vec3 os = o.cwiseQuotient(h);
      const Vec3 ds = d.cwiseQuotient(h);
      double t = 0.0;
      if (smallest_root(ds.squaredNorm(), 2.0 * os.dot(ds), os.squaredNorm() - 1.0, t_min, best,
                        &t)) {
        best = t;
        const Vec3 p = o + t * d;
        normal = p.cwiseQuotient(h.cwiseProduct(h)).normalized();
        found = true;
      }
      break;
    }
  }
  if (!found) return false;
  hit->t = best;
  hit->point_in_part = o + best * d;
  hit->normal_in_part = normal;
  return true;
}

bool intersect_object(const SceneObject& object, const Ray& ray, double t_min, SurfaceHit* hit) {
  bool found = false;
  for (std::size_t i = 0; i < object.parts.size(); ++i) {
    if (intersect_part(object.parts[i], object.world_from_part[i], ray, t_min, hit)) {
      hit->object = &object;
      hit->part = static_cast<int>(i);
      found = true;
    }
  }
  return found;
}

namespace {
// Bounding-sphere test, then the parts.
inline void test_object(const SceneObject& object, const Ray& ray, double a, double t_min,
                        SurfaceHit* hit) {
  const Vec3 oc = ray.origin - object.bound_center;
  const double b = oc.dot(ray.direction);
  const double c = oc.squaredNorm() - object.bound_radius * object.bound_radius;
  const double disc = b * b - a * c;
  if (disc < 0.0) return;
  const double s = std::sqrt(disc);
  if ((-b + s) / a <= t_min || (-b - s) / a >= hit->t) return;
  intersect_object(object, ray, t_min, hit);
}
}  // namespace

SurfaceHit cast_ray(const Scene& scene, const Ray& ray, double t_min) {
  SurfaceHit hit;
  const double a = ray.direction.squaredNorm();
  for (const auto& o : scene.structure) test_object(o, ray, a, t_min, &hit);
  for (const auto& o : scene.objects) test_object(o, ray, a, t_min, &hit);
  return hit;
}

SurfaceHit cast_ray(const std::vector<const SceneObject*>& objects, const Ray& ray, double t_min) {
  SurfaceHit hit;
  const double a = ray.direction.squaredNorm();
  for (const SceneObject* o : objects) test_object(*o, ray, a, t_min, &hit);
  return hit;
}

const Material& material_at(const Part& part, const Vec3& n) {
  if (part.face_materials.size() != 6 || part.shape != Shape::kBox) return part.material;
  int axis = 0;
  n.cwiseAbs().maxCoeff(&axis);
  return part.face_materials[2 * axis + (n[axis] > 0.0 ? 1 : 0)];
}

double distance_to_part_surface(const Part& part, const Vec3& p) {
  const Vec3& h = part.half_extent;
  switch (part.shape) {
    case Shape::kBox: {
      const Vec3 q = p.cwiseAbs() - h;
      if ((q.array() <= 0.0).all()) return -q.maxCoeff();
      return q.cwiseMax(0.0).norm();
    }
    case Shape::kCylinder: {
      const double dr = std::hypot(p.x(), p.y()) - h.x();
      const double dz = std::abs(p.z()) - h.z();
      if (dr <= 0.0 && dz <= 0.0) return -std::max(dr, dz);
      return std::hypot(std::max(dr, 0.0), std::max(dz, 0.0));
    }
    case Shape::kEllipsoid: {
      const double k0 = p.cwiseQuotient(h).norm();
      const double k1 = p.cwiseQuotient(h.cwiseProduct(h)).norm();
      if (k1 <= 0.0) return h.minCoeff();
      return std::abs(k0 * (k0 - 1.0) / k1);
    }
  }
  return 0.0;
}

bool inside_part(const Part& part, const Vec3& p) {
  const Vec3& h = part.half_extent;
  switch (part.shape) {
    case Shape::kBox:
      return (p.cwiseAbs().array() <= h.array()).all();
    case Shape::kCylinder:
      return std::abs(p.z()) <= h.z() && p.x() * p.x() + p.y() * p.y() <= h.x() * h.x();
    case Shape::kEllipsoid:
      return p.cwiseQuotient(h).squaredNorm() <= 1.0;
  }
  return false;
}

double distance_to_surface(const SceneObject& object, const Vec3& point_in_world) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < object.parts.size(); ++i) {
    const Vec3 p = object.world_from_part[i].inverse() * point_in_world;
    best = std::min(best, distance_to_part_surface(object.parts[i], p));
  }
  return best;
}

bool inside_object(const SceneObject& object, const Vec3& point_in_world) {
  for (std::size_t i = 0; i < object.parts.size(); ++i)
    if (inside_part(object.parts[i], object.world_from_part[i].inverse() * point_in_world))
      return true;
  return false;
}

}  // namespace objmap::sim
