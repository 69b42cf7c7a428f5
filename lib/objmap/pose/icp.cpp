#include "objmap/pose/icp.h"

#include <flann/flann.hpp>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "objmap/core/error.h"

namespace objmap::pose {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

void IcpOptions::check() const {
  require(std::isfinite(max_correspondence_m) && max_correspondence_m > 0,
          "IcpOptions.max_correspondence_m", "must be > 0");
  require(max_iterations >= 1, "IcpOptions.max_iterations", "must be >= 1");
  require(normal_neighbours >= 3, "IcpOptions.normal_neighbours", "must be >= 3");
  require(max_points >= 3, "IcpOptions.max_points", "must be >= 3");
  require(max_model_points >= 3, "IcpOptions.max_model_points", "must be >= 3");
  require(std::isfinite(huber_m) && huber_m > 0, "IcpOptions.huber_m", "must be > 0");
  require(std::isfinite(inlier_distance_m) && inlier_distance_m > 0, "IcpOptions.inlier_distance_m",
          "must be > 0");
  require(min_inlier_share >= 0 && min_inlier_share <= 1, "IcpOptions.min_inlier_share",
          "must be in [0, 1]");
  require(max_translation_m > 0, "IcpOptions.max_translation_m", "must be > 0");
  require(max_rotation_deg > 0, "IcpOptions.max_rotation_deg", "must be > 0");
  require(convergence_m > 0, "IcpOptions.convergence_m", "must be > 0");
  require(min_constraint > 0 && min_constraint < 1, "IcpOptions.min_constraint",
          "must be in (0, 1)");
}

// The model's kd-tree is FLANN's single kd-tree (the one PCL's KdTreeFLANN builds, leaves of 15
// points, exact search), queried a whole cloud at a time: one call per ICP iteration instead of one
// per point (bench: docs/pose.md).
using KdIndex = flann::Index<flann::L2_Simple<float>>;

struct ModelAligner::Impl {
  IcpOptions options;
  std::vector<float> xyz;  // the model points, 3 floats each (the kd-tree's data)
  std::unique_ptr<KdIndex> index;
  std::vector<Vec3> points;
  std::vector<Vec3> normals;  // zero where the neighbourhood is not a surface
  Vec3 centroid = Vec3::Zero();
};

ModelAligner::ModelAligner(const PointCloud& model, const IcpOptions& options)
    : impl_(std::make_unique<Impl>()) {
  options.check();
  impl_->options = options;
  const std::size_t stride = (model.size() + options.max_model_points - 1) /
                             std::max<std::size_t>(1, options.max_model_points);
  const std::size_t n = stride > 0 ? (model.size() + stride - 1) / stride : 0;
  impl_->xyz.reserve(3 * n);
  impl_->points.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3f& p = model.points[i * stride];
    impl_->xyz.insert(impl_->xyz.end(), {p.x(), p.y(), p.z()});
    impl_->points[i] = p.cast<double>();
    impl_->centroid += impl_->points[i];
  }
  if (n > 0) impl_->centroid /= static_cast<double>(n);
  impl_->normals.assign(n, Vec3::Zero());
  if (n < static_cast<std::size_t>(options.normal_neighbours)) return;
  flann::Matrix<float> data(impl_->xyz.data(), n, 3);
  impl_->index = std::make_unique<KdIndex>(data, flann::KDTreeSingleIndexParams(15));
  impl_->index->buildIndex();
  // Normals: the smallest principal axis of each point's neighbourhood.
  const std::size_t k = static_cast<std::size_t>(options.normal_neighbours);
  std::vector<int> neighbours(n * k);
  std::vector<float> sq(n * k);
  flann::Matrix<int> idx_all(neighbours.data(), n, k);
  flann::Matrix<float> sq_all(sq.data(), n, k);
  flann::SearchParams params(-1, 0.0f, /*sorted=*/false);
  impl_->index->knnSearch(data, idx_all, sq_all, k, params);
  for (std::size_t i = 0; i < n; ++i) {
    const int* idx = neighbours.data() + i * k;
    const int found = static_cast<int>(k);
    Vec3 mean = Vec3::Zero();
    for (int j = 0; j < found; ++j) mean += impl_->points[idx[j]];
    mean /= found;
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (int j = 0; j < found; ++j) {
      const Vec3 d = impl_->points[idx[j]] - mean;
      cov += d * d.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    // Not a surface: the neighbours lie on a line (or are one point).
    if (eig.eigenvalues()(1) > 1e-3 * eig.eigenvalues()(2) && eig.eigenvalues()(2) > 0)
      impl_->normals[i] = eig.eigenvectors().col(0);
  }
}

ModelAligner::~ModelAligner() = default;
ModelAligner::ModelAligner(ModelAligner&&) noexcept = default;
ModelAligner& ModelAligner::operator=(ModelAligner&&) noexcept = default;

std::size_t ModelAligner::model_points() const { return impl_->points.size(); }

IcpResult ModelAligner::align(const PointCloud& observation) const {
  const IcpOptions& o = impl_->options;
  IcpResult result;
  if (impl_->points.size() < static_cast<std::size_t>(o.normal_neighbours) || observation.empty())
    return result;
  // Thinned observation, in the world frame.
  const std::size_t stride = (observation.size() + o.max_points - 1) / o.max_points;
  std::vector<Vec3> source;
  for (std::size_t i = 0; i < observation.size(); i += stride)
    source.push_back(observation.points[i].cast<double>());
  result.points = source.size();
  Vec3 centre = Vec3::Zero();
  for (const Vec3& p : source) centre += p;
  centre /= static_cast<double>(source.size());

  // Rotations are scaled by the observation's radius, so that both halves of the update have
  // comparable units (metres of motion of its points).
  double radius_sq = 0.0;
  for (const Vec3& p : source) radius_sq += (p - centre).squaredNorm();
  const double radius = std::max(1e-3, std::sqrt(radius_sq / static_cast<double>(source.size())));
  Pose total = Pose::Identity();
  double max_sq = o.max_correspondence_m * o.max_correspondence_m;
  const std::size_t m = source.size();
  std::vector<float> query(3 * m), sq(m);
  std::vector<int> nearest(m);
  std::vector<Vec3> placed(m);
  flann::Matrix<float> query_mat(query.data(), m, 3), sq_mat(sq.data(), m, 1);
  flann::Matrix<int> nearest_mat(nearest.data(), m, 1);
  const flann::SearchParams params(-1, 0.0f, /*sorted=*/false);
  auto pairs = [&](const Pose& t, std::size_t& inliers, double& sum_sq,
                   Eigen::Matrix<double, 6, 6>* jtj, Eigen::Matrix<double, 6, 1>* jtr) {
    inliers = 0;
    sum_sq = 0;
    if (jtj) jtj->setZero(), jtr->setZero();
    // Every point's nearest model point in one query.
    for (std::size_t i = 0; i < m; ++i) {
      placed[i] = t * source[i];
      for (int c = 0; c < 3; ++c) query[3 * i + c] = static_cast<float>(placed[i][c]);
    }
    impl_->index->knnSearch(query_mat, nearest_mat, sq_mat, 1, params);
    for (std::size_t i = 0; i < m; ++i) {
      const Vec3& p = placed[i];
      if (nearest[i] < 0 || sq[i] > max_sq) continue;
      const Vec3& n = impl_->normals[nearest[i]];
      if (n.isZero()) continue;
      ++inliers;
      const double r = n.dot(p - impl_->points[nearest[i]]);
      sum_sq += r * r;
      if (!jtj) continue;
      const double w = std::abs(r) <= o.huber_m ? 1.0 : o.huber_m / std::abs(r);
      Eigen::Matrix<double, 6, 1> j;
      j.head<3>() = (p - centre).cross(n) / radius;
      j.tail<3>() = n;
      *jtj += w * j * j.transpose();
      *jtr += w * j * r;
    }
  };
  std::size_t inliers = 0;
  double sum_sq = 0;
  for (int it = 0; it < o.max_iterations; ++it) {
    Eigen::Matrix<double, 6, 6> jtj;
    Eigen::Matrix<double, 6, 1> jtr;
    pairs(total, inliers, sum_sq, &jtj, &jtr);
    result.iterations = it + 1;
    if (inliers < 6) break;
    // Directions the surface does not constrain (a plane sliding in itself, a bottle turning
    // about its axis) are left out of the update: they stay where they are.
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(jtj);
    const double largest = eig.eigenvalues()(5);
    Eigen::Matrix<double, 6, 1> xi = Eigen::Matrix<double, 6, 1>::Zero();
    for (int k = 0; k < 6; ++k) {
      const double l = eig.eigenvalues()(k);
      if (l > o.min_constraint * largest)
        xi -= eig.eigenvectors().col(k) * (eig.eigenvectors().col(k).dot(jtr) / l);
    }
    const Vec3 w = xi.head<3>() / radius;
    Pose step = Pose::Identity();
    if (w.norm() > 0)
      step.linear() = Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
    step.translation() = centre + xi.tail<3>() - step.linear() * centre;
    // The centre moves with the points: keep rotating about the observation's current centre.
    total = step * total;
    centre = step * centre;
    if (xi.norm() < o.convergence_m) break;
  }
  // The uncertainty at the end: covariance rms² · H⁻¹ of the (radius-scaled rotation,
  // translation) update.
  {
    Eigen::Matrix<double, 6, 6> jtj;
    Eigen::Matrix<double, 6, 1> jtr;
    pairs(total, inliers, sum_sq, &jtj, &jtr);
    const double variance = inliers > 6 ? sum_sq / static_cast<double>(inliers - 6) : 0.0;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(jtj);
    const double largest = eig.eigenvalues()(5);
    if (inliers <= 6 || !(eig.eigenvalues()(0) > 1e-12 * largest)) {
      result.rotation_sigma_deg = result.translation_sigma_m =
          std::numeric_limits<double>::infinity();
    } else {
      const Eigen::Matrix<double, 6, 6> cov = variance * eig.eigenvectors() *
                                              eig.eigenvalues().cwiseInverse().asDiagonal() *
                                              eig.eigenvectors().transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> rot(cov.topLeftCorner<3, 3>());
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> trans(cov.bottomRightCorner<3, 3>());
      result.rotation_sigma_deg =
          std::sqrt(std::max(0.0, rot.eigenvalues()(2))) / radius * 180.0 / kPi;
      result.translation_sigma_m = std::sqrt(std::max(0.0, trans.eigenvalues()(2)));
    }
  }
  result.centre = centre;
  // The final pairs: only points within inlier_distance_m of the model count.
  max_sq = std::min(max_sq, o.inlier_distance_m * o.inlier_distance_m);
  pairs(total, inliers, sum_sq, nullptr, nullptr);
  result.correction = total;
  result.inlier_share = static_cast<double>(inliers) / static_cast<double>(source.size());
  result.rms_m = inliers > 0 ? std::sqrt(sum_sq / static_cast<double>(inliers)) : 0.0;
  const double turned = Eigen::AngleAxisd(total.linear()).angle() * 180.0 / kPi;
  // The translation that matters: how far the model's centroid moves relative to the view.
  const Vec3 moved_point = total.inverse() * impl_->centroid;
  const double moved = (moved_point - impl_->centroid).norm();
  result.aligned = result.inlier_share >= o.min_inlier_share && moved <= o.max_translation_m &&
                   turned <= o.max_rotation_deg;
  return result;
}

}  // namespace objmap::pose
