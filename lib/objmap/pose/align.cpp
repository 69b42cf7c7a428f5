#include "objmap/pose/align.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <string>

#include "objmap/core/error.h"

namespace objmap::pose {

// Why not Eigen::umeyama (Eigen/Geometry, which eval/ate.cpp uses): it takes no weights, and pose
// correction weighs every pair by its observation's weight over the landmark's variance (eq 20,
// pose/correct.cpp), so the weighted means and the weighted cross-covariance are written here.
// Otherwise this is Umeyama's method step for step (the SVD of the cross-covariance, the sign fix
// S, t = mean_target - R mean_source); the tests check that it gives Eigen::umeyama's answer
// without weights, and with whole weights that of each pair repeated as often as its weight.
Pose align_rigid(const std::vector<Vec3>& source, const std::vector<Vec3>& target,
                 const std::vector<double>& weights) {
  require(source.size() == target.size(), "align_rigid",
          std::to_string(source.size()) + " source and " + std::to_string(target.size()) +
              " target points; expected the same count");
  require(!source.empty(), "align_rigid", "no point pair; expected at least one");
  require(weights.empty() || weights.size() == source.size(), "align_rigid",
          "weights must be empty or one per pair");
  const auto w = [&](std::size_t i) { return weights.empty() ? 1.0 : weights[i]; };
  // 1. Weighted means.
  double total = 0.0;
  Vec3 mean_source = Vec3::Zero(), mean_target = Vec3::Zero();
  for (std::size_t i = 0; i < source.size(); ++i) {
    require(w(i) >= 0.0, "align_rigid", "weights must be >= 0");
    total += w(i);
    mean_source += w(i) * source[i];
    mean_target += w(i) * target[i];
  }
  require(total > 0.0, "align_rigid", "weights sum to 0; expected a positive sum");
  mean_source /= total;
  mean_target /= total;
  // 2. Cross-covariance and its SVD; the sign fix keeps R a rotation (Umeyama's S).
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < source.size(); ++i)
    covariance += w(i) * (target[i] - mean_target) * (source[i] - mean_source).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance,
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d s = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) s(2, 2) = -1.0;
  const Eigen::Matrix3d rotation = svd.matrixU() * s * svd.matrixV().transpose();
  Pose target_from_source = Pose::Identity();
  target_from_source.linear() = rotation;
  target_from_source.translation() = mean_target - rotation * mean_source;
  return target_from_source;
}

double spread_m(const std::vector<Vec3>& points) {
  if (points.size() < 3) return 0.0;
  Vec3 mean = Vec3::Zero();
  for (const Vec3& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Vec3& p : points) covariance += (p - mean) * (p - mean).transpose();
  covariance /= static_cast<double>(points.size());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(covariance);
  // Eigenvalues ascending: index 1 is the second largest.
  return std::sqrt(std::max(0.0, eig.eigenvalues()(1)));
}

}  // namespace objmap::pose
