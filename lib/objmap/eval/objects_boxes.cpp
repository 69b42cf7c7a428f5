// The object evaluation's geometry: the assignment of objects and the overlap of oriented boxes.
#include "objmap/eval/objects.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <tuple>

#include "objmap/core/error.h"
#include "objmap/core/format.h"
#include "objmap/core/json_vec.h"
#include "objmap/eval/json.h"
#include "objmap/io/json_file.h"
#include "objmap/io/text_lines.h"
#include "objmap/segmentation/coco_classes.h"
#include "objmap/track/assignment.h"

namespace objmap::eval {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

// ---- assignment
// ---------------------------------------------------------------------------------

std::vector<int> hungarian_assign(const Eigen::MatrixXd& cost) {
  const int rows = static_cast<int>(cost.rows()), cols = static_cast<int>(cost.cols());
  std::vector<int> row_to_col(rows, -1);
  if (rows == 0 || cols == 0) return row_to_col;
  // Forbidden pairs get a cost BIG larger than any sum of min(rows, cols) allowed costs (after
  // shifting them to >= 0), so that the optimum first has the fewest forbidden pairs, then the
  // least total cost; the shared Kuhn-Munkres (track/assignment.h) solves that finite problem.
  double min_allowed = kInf, max_allowed = -kInf;
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j)
      if (std::isfinite(cost(i, j))) {
        min_allowed = std::min(min_allowed, cost(i, j));
        max_allowed = std::max(max_allowed, cost(i, j));
      }
  if (!std::isfinite(min_allowed)) return row_to_col;  // nothing allowed
  const double big = (max_allowed - min_allowed + 1.0) * (std::min(rows, cols) + 1);
  Eigen::MatrixXd finite(rows, cols);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j)
      finite(i, j) = std::isfinite(cost(i, j)) ? cost(i, j) - min_allowed : big;
  const std::vector<int> assigned = track::solve_assignment(finite);
  for (int i = 0; i < rows; ++i)
    if (assigned[i] >= 0 && std::isfinite(cost(i, assigned[i]))) row_to_col[i] = assigned[i];
  return row_to_col;
}

// ---- oriented boxes
// -----------------------------------------------------------------------------

namespace {

using Polygon = std::vector<Vec3>;  // a convex planar polygon, vertices in cyclic order

// The six faces of a box, each as 4 corners in cyclic order.
std::vector<Polygon> box_faces(const Obb& box) {
  std::vector<Polygon> faces;
  for (int axis = 0; axis < 3; ++axis) {
    const int j = (axis + 1) % 3, k = (axis + 2) % 3;
    for (const double side : {-1.0, 1.0}) {
      Polygon face;
      const double sj[4] = {-1, 1, 1, -1}, sk[4] = {-1, -1, 1, 1};
      for (int corner = 0; corner < 4; ++corner) {
        Vec3 local = Vec3::Zero();
        local[axis] = side * box.half_extent[axis];
        local[j] = sj[corner] * box.half_extent[j];
        local[k] = sk[corner] * box.half_extent[k];
        face.push_back(box.center + box.rotation * local);
      }
      faces.push_back(face);
    }
  }
  return faces;
}

// Keeps the part of the convex polyhedron `faces` where normal·x <= offset; closes the cut with a
// cap polygon. `eps` is the distance under which a point counts as on the plane.
std::vector<Polygon> clip_polyhedron(const std::vector<Polygon>& faces, const Vec3& normal,
                                     double offset, double eps) {
  std::vector<Polygon> out;
  std::vector<Vec3> cap;
  bool face_in_plane = false;
  for (const Polygon& face : faces) {
    Polygon kept;
    const std::size_t k = face.size();
    for (std::size_t i = 0; i < k; ++i) {
      const Vec3& cur = face[i];
      const Vec3& next = face[(i + 1) % k];
      const double dc = normal.dot(cur) - offset, dn = normal.dot(next) - offset;
      if (dc <= eps) {
        kept.push_back(cur);
        if (dc >= -eps) cap.push_back(cur);
      }
      if ((dc < -eps && dn > eps) || (dc > eps && dn < -eps)) {
        const Vec3 p = cur + (dc / (dc - dn)) * (next - cur);
        kept.push_back(p);
        cap.push_back(p);
      }
    }
    if (kept.size() < 3) continue;
    // A face lying in the plane already closes the cut: no cap then.
    bool in_plane = true;
    for (const Vec3& p : kept) in_plane = in_plane && std::abs(normal.dot(p) - offset) <= eps;
    face_in_plane = face_in_plane || in_plane;
    out.push_back(std::move(kept));
  }
  if (face_in_plane) return out;
  // The cap: the distinct points on the plane, in angular order around their mean.
  std::vector<Vec3> unique;
  for (const Vec3& p : cap) {
    bool seen = false;
    for (const Vec3& q : unique) seen = seen || (p - q).norm() <= 10 * eps;
    if (!seen) unique.push_back(p);
  }
  if (unique.size() >= 3) {
    Vec3 mean = Vec3::Zero();
    for (const Vec3& p : unique) mean += p;
    mean /= static_cast<double>(unique.size());
    const Vec3 e1 = normal.unitOrthogonal(), e2 = normal.cross(e1);
    std::vector<std::pair<double, Vec3>> by_angle;
    for (const Vec3& p : unique)
      by_angle.push_back({std::atan2(e2.dot(p - mean), e1.dot(p - mean)), p});
    std::sort(by_angle.begin(), by_angle.end(),
              [](const auto& x, const auto& y) { return x.first < y.first; });
    Polygon polygon;
    for (const auto& entry : by_angle) polygon.push_back(entry.second);
    out.push_back(std::move(polygon));
  }
  return out;
}

// Volume of a convex polyhedron given by its face polygons: pyramids from an interior point.
double polyhedron_volume(const std::vector<Polygon>& faces) {
  Vec3 inside = Vec3::Zero();
  std::size_t count = 0;
  for (const Polygon& face : faces)
    for (const Vec3& p : face) {
      inside += p;
      ++count;
    }
  if (count == 0) return 0.0;
  inside /= static_cast<double>(count);
  double volume = 0.0;
  for (const Polygon& face : faces) {
    Vec3 area2 = Vec3::Zero();  // twice the vector area
    for (std::size_t i = 1; i + 1 < face.size(); ++i)
      area2 += (face[i] - face[0]).cross(face[i + 1] - face[0]);
    volume += std::abs(area2.dot(face[0] - inside)) / 6.0;
  }
  return volume;
}

}  // namespace

double obb_volume(const Obb& box) {
  return 8.0 * std::max(0.0, box.half_extent.x()) * std::max(0.0, box.half_extent.y()) *
         std::max(0.0, box.half_extent.z());
}

double obb_intersection_volume(const Obb& a, const Obb& b) {
  if (obb_volume(a) <= 0.0 || obb_volume(b) <= 0.0) return 0.0;
  // Bounding spheres apart: no overlap.
  if ((a.center - b.center).norm() > a.half_extent.norm() + b.half_extent.norm()) return 0.0;
  const double scale =
      1.0 + a.center.norm() + b.center.norm() + a.half_extent.norm() + b.half_extent.norm();
  const double eps = 1e-12 * scale;
  std::vector<Polygon> faces = box_faces(a);
  for (int axis = 0; axis < 3 && !faces.empty(); ++axis)
    for (const double side : {-1.0, 1.0}) {
      // Half-space of b: side · axis_b · (x − c_b) <= h_b[axis].
      const Vec3 normal = side * b.rotation.col(axis);
      const double offset = normal.dot(b.center) + b.half_extent[axis];
      faces = clip_polyhedron(faces, normal, offset, eps);
      if (faces.size() < 4) return 0.0;  // nothing with volume left
    }
  return std::min(polyhedron_volume(faces), std::min(obb_volume(a), obb_volume(b)));
}

double obb_iou(const Obb& a, const Obb& b) {
  const double inter = obb_intersection_volume(a, b);
  const double uni = obb_volume(a) + obb_volume(b) - inter;
  if (uni <= 0.0) return 0.0;
  return std::clamp(inter / uni, 0.0, 1.0);
}

}  // namespace objmap::eval
