#pragma once
#include <vector>

#include "objmap/change/register.h"
#include "objmap/core/types.h"

// The dense part of the registration (register.cpp): PCL's ICP restricted to yaw + translation,
// its fitness and its uncertainty. Private to the change module; no PCL here either.
namespace objmap::change::detail {

// 4-DoF least squares: the yaw about z and the translation that take `source` onto `target`
// (paired by index, at least 2 pairs with a horizontal spread; else the identity rotation).
Pose fit_yaw_translation(const std::vector<Vec3>& source, const std::vector<Vec3>& target);

// One point per occupied voxel (the first point, in input order), then at most max_points of them
// (every n-th). Deterministic.
std::vector<Vec3f> thin_cloud(const std::vector<Vec3f>& points, double voxel_m,
                              std::size_t max_points);

struct DenseFit {
  Pose target_from_source = Pose::Identity();
  double fitness = 0.0;  // the larger of the two shares of points within inlier_m of the other map
  double fitness_both = 0.0;  // the smaller of the two
  double rms_m = 0.0;         // of the source points' inlier distances
  std::size_t source_points = 0;
  double sigma_translation_m = 0.0;
  double sigma_yaw_deg = 0.0;
};

// Both clouds in their gravity frames (z up), each one point per voxel. refine: PCL ICP (yaw +
// translation only) from `guess`, in rounds of shrinking correspondence distance, with at most
// options.icp_max_points of `source` (evenly thinned); else `guess` is only scored. When `source`
// has over 1.5 times the points of `target` (a short visit inside a long one), ICP moves `target`
// instead: its points have a counterpart in the larger map, while the larger's extra surfaces
// would pair with wrong ones; the result is turned back to target_from_source.
DenseFit align_dense(const std::vector<Vec3f>& target, const std::vector<Vec3f>& source,
                     const Pose& guess, const RegistrationOptions& options, bool refine);

// For each guess (target_from_source), the share of `source` points within `inlier_m` of `target`
// (one kd-tree for all): a cheap score to rank many placements before any ICP.
std::vector<double> overlap_shares(const std::vector<Vec3f>& target,
                                   const std::vector<Vec3f>& source,
                                   const std::vector<Pose>& guesses, double inlier_m);

}  // namespace objmap::change::detail
