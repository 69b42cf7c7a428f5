#include "objmap/eval/ate.h"

#include <Eigen/Geometry>
#include <cmath>

#include "objmap/core/error.h"
#include "objmap/core/format.h"

namespace objmap::eval {

void AteOptions::check() const {
  require(std::isfinite(max_diff_s) && max_diff_s > 0.0, "AteOptions.max_diff_s",
          "is " + number_text(max_diff_s) + "; expected a finite number of seconds > 0");
  require(std::isfinite(offset_s), "AteOptions.offset_s",
          "is " + number_text(offset_s) + "; expected a finite number of seconds");
}

Vec3 Similarity::operator*(const Vec3& point_in_source) const {
  return scale * (rotation * point_in_source) + translation;
}

Pose Similarity::apply(const Pose& source_world_from_cam) const {
  Pose pose = Pose::Identity();
  pose.linear() = rotation * source_world_from_cam.linear();
  pose.translation() = (*this) * source_world_from_cam.translation();
  return pose;
}

Similarity align_points(const std::vector<Vec3>& source, const std::vector<Vec3>& target,
                        bool with_scale) {
  require(source.size() == target.size() && !source.empty(), "align_points",
          std::to_string(source.size()) + " source and " + std::to_string(target.size()) +
              " target points; expected the same number, at least 1");
  // Umeyama (1991), as evaluate_ate.py's `align` (model = estimate, data = ground truth): R proper,
  // s = tr(D S) / (n σ²_source) with a scale, else 1.
  const Eigen::Index n = static_cast<Eigen::Index>(source.size());
  Eigen::Matrix3Xd source_m(3, n), target_m(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    source_m.col(i) = source[static_cast<std::size_t>(i)];
    target_m.col(i) = target[static_cast<std::size_t>(i)];
  }
  if (with_scale)
    require(
        (source_m.colwise() - source_m.rowwise().mean()).squaredNorm() > 0.0, "align_points",
        "all estimate positions coincide; expected a trajectory that moves to estimate a scale");
  const Eigen::Matrix4d target_from_source = Eigen::umeyama(source_m, target_m, with_scale);
  Similarity result;
  if (with_scale) result.scale = target_from_source.col(0).head<3>().norm();  // the columns of s R
  result.rotation = target_from_source.topLeftCorner<3, 3>() / result.scale;
  result.translation = target_from_source.topRightCorner<3, 1>();
  return result;
}

AteResult evaluate_ate(const Trajectory& gt, const Trajectory& est, const AteOptions& options) {
  options.check();
  AteResult result;
  result.gt_source = gt.source;
  result.est_source = est.source;
  // 1. Associate the stamps (associate.py); evaluate_ate.py needs at least 2 pairs.
  AssociateOptions association;
  association.max_diff_s = options.max_diff_s;
  association.offset_s = options.offset_s;
  result.matches = associate(gt, est, association);
  require_pairs(result.matches, 2, gt, est, association);
  std::vector<std::size_t> gt_used, est_used;
  for (const StampMatch& m : result.matches) {
    gt_used.push_back(m.gt_index);
    est_used.push_back(m.est_index);
  }
  require_plausible_positions(gt, gt_used);
  require_plausible_positions(est, est_used);

  // 2. Align the estimate's positions onto the ground truth's (evaluate_ate.py `align`).
  std::vector<Vec3> est_points, gt_points;
  est_points.reserve(result.matches.size());
  gt_points.reserve(result.matches.size());
  for (const StampMatch& m : result.matches) {
    est_points.push_back(est.poses[m.est_index].world_from_cam.translation());
    gt_points.push_back(gt.poses[m.gt_index].world_from_cam.translation());
  }
  result.gt_from_est = align_points(est_points, gt_points, options.with_scale);

  // 3. Translational error of each pair and its statistics.
  result.errors_m.reserve(result.matches.size());
  for (std::size_t i = 0; i < est_points.size(); ++i)
    result.errors_m.push_back((result.gt_from_est * est_points[i] - gt_points[i]).norm());
  result.stats = compute_stats(result.errors_m);

  // 4. The whole estimate in the ground truth's world (for --save-aligned and plots).
  result.aligned.source = est.source;
  result.aligned.poses.reserve(est.size());
  for (const StampedPose& p : est.poses)
    result.aligned.poses.push_back({p.timestamp, result.gt_from_est.apply(p.world_from_cam)});
  return result;
}

}  // namespace objmap::eval
