#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

#include "objmap/core/trajectory.h"
#include "objmap/core/types.h"
#include "objmap/eval/associate.h"
#include "objmap/eval/stats.h"

// Absolute trajectory error as the TUM RGB-D benchmark's evaluate_ate.py: associate the stamps
// (associate.py), align the estimate's positions onto the ground truth's in closed form (Horn's
// problem solved by SVD, evaluate_ate.py's `align`; optionally with a scale, Umeyama 1991), and
// take the distances between the aligned estimate and the ground truth positions.
namespace objmap::eval {

struct AteOptions {
  double max_diff_s = 0.02;  // evaluate_ate.py --max_difference: |t_gt − (t_est + offset)| < this
  double offset_s = 0.0;     // evaluate_ate.py --offset: added to the estimate's stamps
  bool with_scale = false;  // false: rigid SE(3) alignment (evaluate_ate.py); true: Sim(3) with the
                            // scale estimated (Umeyama), for monocular runs of unknown scale
  void check() const;       // throws InputError naming the bad field
};

// A similarity transform target_from_source: p_target = scale · rotation · p_source + translation.
struct Similarity {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Vec3 translation = Vec3::Zero();
  double scale = 1.0;

  Vec3 operator*(const Vec3& point_in_source) const;
  // A pose world_from_cam of the source world mapped into the target world: the rotation turns
  // with `rotation`, the position is mapped as a point (a scale changes no orientation).
  Pose apply(const Pose& source_world_from_cam) const;
};

// Least-squares target_from_source for corresponding points (same count, >= 1; the caller requires
// enough of them): minimises Σ‖target_i − (s R source_i + t)‖² with R a proper rotation; s = 1
// unless `with_scale` (Eigen::umeyama). Throws InputError when `with_scale` and the source points
// all coincide.
Similarity align_points(const std::vector<Vec3>& source, const std::vector<Vec3>& target,
                        bool with_scale);

struct AteResult {
  std::string gt_source, est_source;  // the trajectories' files, for reports
  std::vector<StampMatch> matches;    // associated (gt, est) poses, by time
  std::vector<double> errors_m;       // per match: ‖gt_from_est · p_est − p_gt‖, metres
  ErrorStats stats;                   // of errors_m (metres); stats.count = number of pairs
  Similarity gt_from_est;             // the alignment (scale 1 unless with_scale)
  Trajectory aligned;                 // every pose of the estimate mapped by gt_from_est
};

// Throws InputError "no pose pairs within max_diff ..." when fewer than 2 stamps associate.
AteResult evaluate_ate(const Trajectory& gt, const Trajectory& est, const AteOptions& options);

}  // namespace objmap::eval
