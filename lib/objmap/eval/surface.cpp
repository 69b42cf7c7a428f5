#include "objmap/eval/surface.h"

#include <flann/flann.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

#include "objmap/core/error.h"

namespace objmap::eval {

void SurfaceEvalOptions::check() const {
  require(std::isfinite(sample_spacing_m) && sample_spacing_m >= 1e-4 && sample_spacing_m <= 0.1,
          "sample_spacing_m", "must be in [0.0001, 0.1] m");
  require(std::isfinite(threshold_m) && threshold_m > 0.0, "threshold_m", "must be > 0");
  require(std::isfinite(visible_tolerance_m) && visible_tolerance_m > 0.0, "visible_tolerance_m",
          "must be > 0");
}

namespace {

using KdIndex = flann::Index<flann::L2_Simple<float>>;

// splitmix64: a fixed, portable sequence (samples do not depend on the standard library).
double unit_random(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * (1.0 / 9007199254740992.0);
}

// Closest point to p on triangle abc (Ericson, Real-Time Collision Detection, 5.1.5).
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// Float rows for FLANN.
std::vector<float> packed(const std::vector<Vec3>& points) {
  std::vector<float> out;
  out.reserve(points.size() * 3);
  for (const Vec3& p : points)
    for (int a = 0; a < 3; ++a) out.push_back(static_cast<float>(p[a]));
  return out;
}

}  // namespace

SurfaceSamples sample_mesh(const TriangleMesh& mesh, double spacing_m) {
  SurfaceSamples out;
  const double per_m2 = 1.0 / (spacing_m * spacing_m);
  double carry = 0.0;
  std::uint64_t state = 0x5eed;
  for (const auto& t : mesh.triangles) {
    const Vec3 a = mesh.vertices[t[0]].cast<double>(), b = mesh.vertices[t[1]].cast<double>(),
               c = mesh.vertices[t[2]].cast<double>();
    const Vec3 cross = (b - a).cross(c - a);
    const double area = 0.5 * cross.norm();
    carry += area * per_m2;
    const int n = static_cast<int>(std::floor(carry));
    carry -= n;
    const Vec3 normal = cross.norm() > 0 ? Vec3(cross.normalized()) : Vec3::UnitZ();
    for (int k = 0; k < n; ++k) {
      const double s = std::sqrt(unit_random(state)), r = unit_random(state);
      out.points.push_back((1 - s) * a + s * (1 - r) * b + s * r * c);
      out.normals.push_back(normal);
    }
  }
  return out;
}

struct MeshDistance::Impl {
  TriangleMesh mesh;  // a copy: the distance may outlive the mesh it was made of
  std::vector<float> centroids;
  std::unique_ptr<KdIndex> tree;
  explicit Impl(const TriangleMesh& m) : mesh(m) {}
};

MeshDistance::MeshDistance(const TriangleMesh& mesh) : impl_(std::make_unique<Impl>(mesh)) {
  require(!mesh.triangles.empty(), "MeshDistance", "the true surface has no triangles");
  std::vector<Vec3> centres;
  for (const auto& t : mesh.triangles)
    centres.push_back(
        ((mesh.vertices[t[0]] + mesh.vertices[t[1]] + mesh.vertices[t[2]]) / 3.0f).cast<double>());
  impl_->centroids = packed(centres);
  flann::Matrix<float> data(impl_->centroids.data(), centres.size(), 3);
  impl_->tree = std::make_unique<KdIndex>(data, flann::KDTreeSingleIndexParams(15));
  impl_->tree->buildIndex();
}

MeshDistance::~MeshDistance() = default;

// The nearest triangle among those whose centroids are the 16 nearest (the models' triangles are
// small against the distances that matter).
double MeshDistance::operator()(const Vec3& point) const {
  const int k = static_cast<int>(std::min<std::size_t>(16, impl_->mesh.triangles.size()));
  float q[3] = {static_cast<float>(point.x()), static_cast<float>(point.y()),
                static_cast<float>(point.z())};
  std::vector<int> idx(k);
  std::vector<float> sq(k);
  flann::Matrix<float> query(q, 1, 3);
  flann::Matrix<int> idx_m(idx.data(), 1, k);
  flann::Matrix<float> sq_m(sq.data(), 1, k);
  impl_->tree->knnSearch(query, idx_m, sq_m, k, flann::SearchParams(-1, 0.0f, true));
  double best = std::numeric_limits<double>::infinity();
  for (int i : idx) {
    const auto& t = impl_->mesh.triangles[static_cast<std::size_t>(i)];
    const Vec3 c = closest_on_triangle(point, impl_->mesh.vertices[t[0]].cast<double>(),
                                       impl_->mesh.vertices[t[1]].cast<double>(),
                                       impl_->mesh.vertices[t[2]].cast<double>());
    best = std::min(best, (c - point).norm());
  }
  return best;
}

std::vector<double> nearest_distances(const std::vector<Vec3>& cloud,
                                      const std::vector<Vec3>& queries) {
  std::vector<double> out(queries.size(), std::numeric_limits<double>::infinity());
  if (cloud.empty() || queries.empty()) return out;
  std::vector<float> data = packed(cloud), query = packed(queries);
  KdIndex tree(flann::Matrix<float>(data.data(), cloud.size(), 3),
               flann::KDTreeSingleIndexParams(15));
  tree.buildIndex();
  std::vector<int> idx(queries.size());
  std::vector<float> sq(queries.size());
  flann::Matrix<float> q(query.data(), queries.size(), 3);
  flann::Matrix<int> idx_m(idx.data(), queries.size(), 1);
  flann::Matrix<float> sq_m(sq.data(), queries.size(), 1);
  tree.knnSearch(q, idx_m, sq_m, 1, flann::SearchParams(-1, 0.0f, true));
  for (std::size_t i = 0; i < queries.size(); ++i) out[i] = std::sqrt(static_cast<double>(sq[i]));
  return out;
}

std::vector<bool> seen_samples(const SurfaceSamples& truth, const std::vector<DepthImage>& views,
                               const SurfaceEvalOptions& options) {
  std::vector<bool> seen(truth.points.size(), false);
  for (const DepthImage& v : views) {
    const Pose cam_from_world = v.world_from_cam.inverse();
    const Vec3 eye = v.world_from_cam.translation();
    for (std::size_t i = 0; i < truth.points.size(); ++i) {
      if (seen[i] || truth.normals[i].dot(eye - truth.points[i]) <= 0.0) continue;
      const Vec3 p = cam_from_world * truth.points[i];
      if (p.z() <= 0.0) continue;
      const Eigen::Vector2d px = v.camera.project(p);
      const int u = static_cast<int>(std::lround(px.x())),
                r = static_cast<int>(std::lround(px.y()));
      if (u < 0 || r < 0 || u >= v.depth.cols || r >= v.depth.rows) continue;
      const double d = v.depth.at<std::uint16_t>(r, u) / v.camera.depth_factor;
      seen[i] = d > 0.0 && std::abs(d - p.z()) < options.visible_tolerance_m;
    }
  }
  return seen;
}

SurfaceScores score_surface(const std::vector<Vec3>& reconstruction, const MeshDistance& truth,
                            const std::vector<Vec3>& seen, const SurfaceEvalOptions& options) {
  SurfaceScores s;
  s.reconstruction_samples = reconstruction.size();
  s.truth_samples_seen = seen.size();
  if (reconstruction.empty() || seen.empty()) return s;
  std::vector<double> accuracy(reconstruction.size());
  std::size_t precise = 0;
  for (std::size_t i = 0; i < reconstruction.size(); ++i) {
    accuracy[i] = truth(reconstruction[i]);
    precise += accuracy[i] <= options.threshold_m;
  }
  double sum = 0.0;
  for (double d : accuracy) sum += d;
  s.accuracy_mean_m = sum / static_cast<double>(accuracy.size());
  const std::size_t k90 = static_cast<std::size_t>(0.9 * static_cast<double>(accuracy.size() - 1));
  std::nth_element(accuracy.begin(), accuracy.begin() + static_cast<std::ptrdiff_t>(k90),
                   accuracy.end());
  s.accuracy_p90_m = accuracy[k90];
  std::size_t complete = 0;
  for (double d : nearest_distances(reconstruction, seen)) complete += d <= options.threshold_m;
  s.precision = static_cast<double>(precise) / static_cast<double>(reconstruction.size());
  s.completeness = static_cast<double>(complete) / static_cast<double>(seen.size());
  s.fscore = s.precision + s.completeness > 0.0
                 ? 2.0 * s.precision * s.completeness / (s.precision + s.completeness)
                 : 0.0;
  return s;
}

}  // namespace objmap::eval
