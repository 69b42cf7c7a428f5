#pragma once
#include <vector>

#include "objmap/core/types.h"

// Closed-form rigid alignment of corresponding points (Horn 1987 / Umeyama 1991, the SVD form) and
// the spread of a point set, the evidence test of a per-keyframe correction (paper eqs 19-20).
namespace objmap::pose {

// target_from_source minimising Σ w_i ‖target_i − (R source_i + t)‖² with R a proper rotation.
// `weights` is empty (all 1) or one non-negative weight per pair with a positive sum. Throws
// InputError when the sizes differ or there is no pair. Exact for noise-free pairs that are not
// all collinear (three or more non-collinear points fix the rotation).
Pose align_rigid(const std::vector<Vec3>& source, const std::vector<Vec3>& target,
                 const std::vector<double>& weights = {});

// How well a set of points fixes a rotation: the standard deviation (metres) of the points along
// their second principal axis. 0 for fewer than 3 points or collinear points.
double spread_m(const std::vector<Vec3>& points);

}  // namespace objmap::pose
