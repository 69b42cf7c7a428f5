#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "objmap/core/camera.h"
#include "objmap/core/mesh.h"
#include "objmap/core/types.h"

// Reconstructed surfaces (an object's mesh, or its point cloud) against the true surface (the
// object's model placed in the world): accuracy, completeness and F-score, as the reconstruction
// benchmarks score them (Knapitsch et al. 2017, Tanks and Temples): the distance of the
// reconstruction to the truth, the share of the truth near the reconstruction, their harmonic mean.
namespace objmap::eval {

struct SurfaceEvalOptions {
  double sample_spacing_m = 0.001;  // meshes are sampled at one point per this squared (area)
  double threshold_m = 0.01;        // completeness, precision and F-score at this distance
  // A true-surface sample was seen when, in one of the views, it faces the camera and the measured
  // depth at its pixel is within this of its own depth (not hidden by something else).
  double visible_tolerance_m = 0.01;
  void check() const;  // throws InputError naming the bad field
};

// Points on a mesh, area-weighted (each triangle gets area/spacing^2 samples, the fractions carried
// from one triangle to the next), with the normal of their triangle. Deterministic.
struct SurfaceSamples {
  std::vector<Vec3> points;
  std::vector<Vec3> normals;
};
SurfaceSamples sample_mesh(const TriangleMesh& mesh, double spacing_m);

// The exact distance from a point to a mesh's surface (nearest triangle); keeps a copy of the mesh.
class MeshDistance {
 public:
  explicit MeshDistance(const TriangleMesh& mesh);
  ~MeshDistance();
  double operator()(const Vec3& point) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The distance from each query point to the nearest point of `cloud` (FLANN kd-tree).
std::vector<double> nearest_distances(const std::vector<Vec3>& cloud,
                                      const std::vector<Vec3>& queries);

// A camera view for visibility: its pose and its raw depth image (CV_16UC1, 0 = none).
struct DepthImage {
  Camera camera;
  Pose world_from_cam = Pose::Identity();
  cv::Mat depth;
};

// Which samples at least one view saw (faces it, in the image, the depth there agrees).
std::vector<bool> seen_samples(const SurfaceSamples& truth, const std::vector<DepthImage>& views,
                               const SurfaceEvalOptions& options);

struct SurfaceScores {
  std::size_t reconstruction_samples = 0;  // mesh samples or cloud points
  std::size_t truth_samples_seen = 0;      // of the true surface, seen by the views
  double accuracy_mean_m = 0.0;            // reconstruction -> true surface
  double accuracy_p90_m = 0.0;
  double precision = 0.0;     // share of the reconstruction within threshold of the truth
  double completeness = 0.0;  // share of the seen truth within threshold of the reconstruction
  double fscore = 0.0;        // 2PR/(P+R)
};

// Scores reconstruction points (mesh samples, or a cloud's points) against the true surface:
// `truth` the exact distance to it; `seen` its samples that the views saw.
SurfaceScores score_surface(const std::vector<Vec3>& reconstruction, const MeshDistance& truth,
                            const std::vector<Vec3>& seen, const SurfaceEvalOptions& options);

}  // namespace objmap::eval
