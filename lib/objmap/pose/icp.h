#pragma once
#include <memory>

#include "objmap/core/types.h"

// Point-to-plane ICP of one observation against an object model (both in the world frame): where
// the keyframe's view of an object sits on the fused model. A camera sees one side of an object,
// so the centroid of its points is not the object's centroid; aligned to the model, the view tells
// where the whole model lies as seen from that keyframe (objmap correct, --view-model icp).
namespace objmap::pose {

struct IcpOptions {
  double max_correspondence_m = 0.03;  // an observation point farther from the model is not paired
  int max_iterations = 30;
  int normal_neighbours = 12;     // a model normal: PCA of this many nearest model points
  std::size_t max_points = 2000;  // the observation is thinned (every n-th point) to this many
  std::size_t max_model_points = 20000;  // the model too (its kd-tree and normals)
  double huber_m = 0.005;                // robust weight of a point-to-plane distance beyond this
  double inlier_distance_m = 0.01;  // at the end, a point this close to the model surface is in
  double min_inlier_share = 0.5;    // fewer observation points in at the end: not aligned
  double max_translation_m = 0.05;  // the model's centroid moved farther: not aligned
  double max_rotation_deg = 20.0;   // a larger rotation: not aligned
  double convergence_m = 1e-5;      // stop when an update moves the points less than this
  // A direction of motion whose information is below this share of the best constrained one
  // (the surface does not pin it down) is not updated.
  double min_constraint = 1e-4;
  void check() const;  // throws InputError naming the bad field
};

struct IcpResult {
  bool aligned = false;                // converged within the bounds, enough points paired
  Pose correction = Pose::Identity();  // world-side: correction · observation ≈ model
  double inlier_share = 0.0;           // observation points paired at the end
  double rms_m = 0.0;                  // point-to-plane RMS of the pairs at the end
  int iterations = 0;
  std::size_t points = 0;  // observation points used (after thinning)
  // Uncertainty of the alignment at the end, from the point-to-plane information (rms² · H⁻¹ of
  // the Gauss-Newton problem): the std of its least constrained rotation (about the observation's
  // centre) and translation. A surface that does not pin a direction down (a bottle turning about
  // its axis, a plane sliding in itself) gives a large value (infinity when singular).
  double rotation_sigma_deg = 0.0;
  double translation_sigma_m = 0.0;
  Vec3 centre = Vec3::Zero();  // the observation's centre after the alignment, world frame
};

// A model with its kd-tree and normals, built once and aligned against many observations.
// Thread-safe for concurrent align() calls.
class ModelAligner {
 public:
  ModelAligner(const PointCloud& model_in_world, const IcpOptions& options);
  ~ModelAligner();
  ModelAligner(ModelAligner&&) noexcept;
  ModelAligner& operator=(ModelAligner&&) noexcept;

  std::size_t model_points() const;
  IcpResult align(const PointCloud& observation_in_world) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace objmap::pose
