#pragma once
// Synthetic visits with exact answers for the change tests: a room corner (floor, two walls), a
// table, box-shaped objects sampled on their surfaces, cameras looking at the table.
#include <cmath>
#include <string>
#include <vector>

#include "objmap/change/visit.h"
#include "objmap/core/types.h"

namespace objmap::change::testing {

// Points on the faces of the box [lo, hi] (step metres).
inline std::vector<Vec3f> box_surface(const Vec3& lo, const Vec3& hi, double step) {
  std::vector<Vec3f> out;
  const Vec3 size = hi - lo;
  const int nx = std::max(1, static_cast<int>(size.x() / step)),
            ny = std::max(1, static_cast<int>(size.y() / step)),
            nz = std::max(1, static_cast<int>(size.z() / step));
  for (int i = 0; i <= nx; ++i)
    for (int j = 0; j <= ny; ++j)
      for (int k = 0; k <= nz; ++k) {
        const bool face = i == 0 || i == nx || j == 0 || j == ny || k == 0 || k == nz;
        if (face)
          out.emplace_back(static_cast<float>(lo.x() + size.x() * i / nx),
                           static_cast<float>(lo.y() + size.y() * j / ny),
                           static_cast<float>(lo.z() + size.z() * k / nz));
      }
  return out;
}

struct TestObject {
  int id;
  std::string class_name;
  Vec3 centre;  // box centre, world
  Vec3 half;    // half sizes
};

inline VisitObject make_visit_object(const TestObject& t, double step = 0.01) {
  VisitObject o;
  o.id = t.id;
  o.class_name = t.class_name;
  o.position = t.centre;
  o.half_extent = t.half;
  // Its visible surface: a camera never sees the face it stands on.
  for (const Vec3f& p : box_surface(t.centre - t.half, t.centre + t.half, step))
    if (p.z() > t.centre.z() - t.half.z() + 1e-4) o.points.push_back(p);
  return o;
}

// The room (floor z = 0, walls at x = -1.9 and y = 1), a table top at z = 0.75
// over [-0.8, 0.8] x [-0.45, 0.45], the objects; cameras on a half circle round the table at 1.5 m
// height looking at its centre.
inline Visit make_test_visit(const std::vector<TestObject>& objects, int cameras = 12) {
  Visit v;
  v.name = "test visit";
  const double step = 0.01;
  for (double x = -2.0; x <= 2.0; x += step)
    for (double y = -2.0; y <= 2.0; y += step) {
      v.dense.push_back(Vec3f(x, y, 0.0f));
    }
  for (double s = -2.0; s <= 2.0; s += step)
    for (double z = 0.0; z <= 2.5; z += step) {
      v.dense.push_back(Vec3f(-1.9f, s, z));
      v.dense.push_back(Vec3f(s, 1.0f, z));
    }
  for (double x = -0.8; x <= 0.8; x += 0.01)
    for (double y = -0.45; y <= 0.45; y += 0.01) v.dense.push_back(Vec3f(x, y, 0.75f));
  for (const TestObject& t : objects) {
    VisitObject o = make_visit_object(t);
    for (const Vec3f& p : o.points) v.dense.push_back(p);
    v.objects.push_back(std::move(o));
  }
  v.camera.width = 640;
  v.camera.height = 480;
  v.camera.fx = v.camera.fy = 525.0;
  v.camera.cx = 319.5;
  v.camera.cy = 239.5;
  for (int i = 0; i < cameras; ++i) {
    const double a = -M_PI * (0.1 + 0.8 * i / std::max(1, cameras - 1));  // the -y half circle
    const Vec3 eye(1.6 * std::cos(a), 1.6 * std::sin(a), 1.5);
    const Vec3 target(0, 0, 0.75);
    const Vec3 z = (target - eye).normalized();
    const Vec3 x = z.cross(Vec3::UnitZ()).normalized();
    const Vec3 y = z.cross(x);
    Pose p = Pose::Identity();
    p.linear().col(0) = x;
    p.linear().col(1) = y;
    p.linear().col(2) = z;
    p.translation() = eye;
    v.world_from_cam.push_back(p);
  }
  return v;
}

// The same visit seen in another world frame: everything moved by `new_from_old` (up stays +z).
inline Visit moved_visit(const Visit& v, const Pose& new_from_old) {
  Visit out = v;
  for (Vec3f& p : out.dense.points) p = (new_from_old * p.cast<double>()).cast<float>();
  for (VisitObject& o : out.objects) {
    o.position = new_from_old * o.position;
    for (Vec3f& p : o.points) p = (new_from_old * p.cast<double>()).cast<float>();
  }
  for (Pose& p : out.world_from_cam) p = new_from_old * p;
  return out;
}

inline Pose yaw_shift(double yaw_deg, const Vec3& t) {
  Pose p = Pose::Identity();
  p.linear() = Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Vec3::UnitZ()).matrix();
  p.translation() = t;
  return p;
}

// Seven objects on the table and a chair on the floor.
inline std::vector<TestObject> test_objects() {
  return {{1, "tv", {0.0, 0.3, 0.95}, {0.28, 0.03, 0.2}},
          {2, "keyboard", {0.0, -0.05, 0.765}, {0.22, 0.07, 0.015}},
          {3, "mouse", {0.35, -0.05, 0.77}, {0.03, 0.05, 0.02}},
          {4, "cup", {-0.5, -0.2, 0.8}, {0.04, 0.04, 0.05}},
          {5, "cup", {0.55, 0.2, 0.8}, {0.04, 0.04, 0.05}},
          {6, "bottle", {-0.6, 0.2, 0.87}, {0.035, 0.035, 0.12}},
          {7, "book", {0.5, -0.3, 0.77}, {0.12, 0.085, 0.02}},
          {8, "chair", {-0.3, -0.8, 0.45}, {0.22, 0.22, 0.45}}};
}

}  // namespace objmap::change::testing
