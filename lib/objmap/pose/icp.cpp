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

namespace {

using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Vector6 = Eigen::Matrix<double, 6, 1>;

// The view's points against the model: each point's nearest model point (the whole cloud in one
// kd-tree query), its distance along the model normal there, and on request the Gauss–Newton
// system of the (radius-scaled rotation, translation) update, with Huber weights.
class PointToPlane {
 public:
  PointToPlane(KdIndex& index, const std::vector<Vec3>& model_points,
               const std::vector<Vec3>& normals, const std::vector<Vec3>& source, double huber_m,
               double radius)
      : index_(index),
        model_points_(model_points),
        normals_(normals),
        source_(source),
        huber_m_(huber_m),
        radius_(radius),
        query_(3 * source.size()),
        sq_(source.size()),
        nearest_(source.size()),
        placed_(source.size()) {}

  std::size_t inliers = 0;
  double sum_sq = 0;

  // Pairs of the view moved by t, within sqrt(max_sq) of the model; rotations about `centre`.
  void pair(const Pose& t, const Vec3& centre, double max_sq, Matrix6* jtj, Vector6* jtr) {
    const std::size_t m = source_.size();
    flann::Matrix<float> query_mat(query_.data(), m, 3), sq_mat(sq_.data(), m, 1);
    flann::Matrix<int> nearest_mat(nearest_.data(), m, 1);
    const flann::SearchParams params(-1, 0.0f, /*sorted=*/false);
    inliers = 0;
    sum_sq = 0;
    if (jtj) jtj->setZero(), jtr->setZero();
    // Every point's nearest model point in one query.
    for (std::size_t i = 0; i < m; ++i) {
      placed_[i] = t * source_[i];
      for (int c = 0; c < 3; ++c) query_[3 * i + c] = static_cast<float>(placed_[i][c]);
    }
    index_.knnSearch(query_mat, nearest_mat, sq_mat, 1, params);
    for (std::size_t i = 0; i < m; ++i) {
      const Vec3& p = placed_[i];
      if (nearest_[i] < 0 || sq_[i] > max_sq) continue;
      const Vec3& n = normals_[nearest_[i]];
      if (n.isZero()) continue;
      ++inliers;
      const double r = n.dot(p - model_points_[nearest_[i]]);
      sum_sq += r * r;
      if (!jtj) continue;
      const double w = std::abs(r) <= huber_m_ ? 1.0 : huber_m_ / std::abs(r);
      Vector6 j;
      j.head<3>() = (p - centre).cross(n) / radius_;
      j.tail<3>() = n;
      *jtj += w * j * j.transpose();
      *jtr += w * j * r;
    }
  }

 private:
  KdIndex& index_;
  const std::vector<Vec3>& model_points_;
  const std::vector<Vec3>& normals_;
  const std::vector<Vec3>& source_;
  double huber_m_, radius_;
  std::vector<float> query_, sq_;
  std::vector<int> nearest_;
  std::vector<Vec3> placed_;
};

// The observation thinned to at most max_points points, in the world frame.
std::vector<Vec3> thinned(const PointCloud& observation, std::size_t max_points) {
  const std::size_t stride = (observation.size() + max_points - 1) / max_points;
  std::vector<Vec3> source;
  for (std::size_t i = 0; i < observation.size(); i += stride)
    source.push_back(observation.points[i].cast<double>());
  return source;
}

// Gauss–Newton on the point-to-plane distances. Directions the surface does not constrain (a plane
// sliding in itself, a bottle turning about its axis) are left out of the update: they stay where
// they are. `centre` moves with the points; returns the correction.
Pose gauss_newton(PointToPlane& fit, const IcpOptions& o, double radius, double max_sq,
                  Vec3& centre, IcpResult& result) {
  Pose total = Pose::Identity();
  for (int it = 0; it < o.max_iterations; ++it) {
    Matrix6 jtj;
    Vector6 jtr;
    fit.pair(total, centre, max_sq, &jtj, &jtr);
    result.iterations = it + 1;
    if (fit.inliers < 6) break;
    const Eigen::SelfAdjointEigenSolver<Matrix6> eig(jtj);
    const double largest = eig.eigenvalues()(5);
    Vector6 xi = Vector6::Zero();
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
  return total;
}

// The uncertainty at the end: covariance rms² · H⁻¹ of the (radius-scaled rotation, translation)
// update; infinite when fewer than 7 points pair or a direction is not constrained.
void uncertainty(PointToPlane& fit, const Pose& total, const Vec3& centre, double radius,
                 double max_sq, IcpResult& result) {
  Matrix6 jtj;
  Vector6 jtr;
  fit.pair(total, centre, max_sq, &jtj, &jtr);
  const std::size_t inliers = fit.inliers;
  const double variance = inliers > 6 ? fit.sum_sq / static_cast<double>(inliers - 6) : 0.0;
  const Eigen::SelfAdjointEigenSolver<Matrix6> eig(jtj);
  const double largest = eig.eigenvalues()(5);
  if (inliers <= 6 || !(eig.eigenvalues()(0) > 1e-12 * largest)) {
    result.rotation_sigma_deg = result.translation_sigma_m =
        std::numeric_limits<double>::infinity();
    return;
  }
  const Matrix6 cov = variance * eig.eigenvectors() *
                      eig.eigenvalues().cwiseInverse().asDiagonal() *
                      eig.eigenvectors().transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> rot(cov.topLeftCorner<3, 3>());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> trans(cov.bottomRightCorner<3, 3>());
  result.rotation_sigma_deg = std::sqrt(std::max(0.0, rot.eigenvalues()(2))) / radius * 180.0 / kPi;
  result.translation_sigma_m = std::sqrt(std::max(0.0, trans.eigenvalues()(2)));
}

}  // namespace

IcpResult ModelAligner::align(const PointCloud& observation) const {
  const IcpOptions& o = impl_->options;
  IcpResult result;
  if (impl_->points.size() < static_cast<std::size_t>(o.normal_neighbours) || observation.empty())
    return result;
  // 1. The thinned observation, its centre and radius: rotations are scaled by the radius, so
  //    that both halves of the update have comparable units (metres of motion of its points).
  const std::vector<Vec3> source = thinned(observation, o.max_points);
  result.points = source.size();
  Vec3 centre = Vec3::Zero();
  for (const Vec3& p : source) centre += p;
  centre /= static_cast<double>(source.size());
  double radius_sq = 0.0;
  for (const Vec3& p : source) radius_sq += (p - centre).squaredNorm();
  const double radius = std::max(1e-3, std::sqrt(radius_sq / static_cast<double>(source.size())));
  PointToPlane fit(*impl_->index, impl_->points, impl_->normals, source, o.huber_m, radius);

  // 2. Point-to-plane Gauss–Newton within the correspondence distance.
  const double max_sq = o.max_correspondence_m * o.max_correspondence_m;
  const Pose total = gauss_newton(fit, o, radius, max_sq, centre, result);

  // 3. The uncertainty of the correction.
  uncertainty(fit, total, centre, radius, max_sq, result);
  result.centre = centre;

  // 4. The final pairs: only points within inlier_distance_m of the model count.
  fit.pair(total, centre, std::min(max_sq, o.inlier_distance_m * o.inlier_distance_m), nullptr,
           nullptr);
  result.correction = total;
  result.inlier_share = static_cast<double>(fit.inliers) / static_cast<double>(source.size());
  result.rms_m = fit.inliers > 0 ? std::sqrt(fit.sum_sq / static_cast<double>(fit.inliers)) : 0.0;

  // 5. Aligned when enough points pair and the model moves within the bounds; the translation
  //    that matters is how far the model's centroid moves relative to the view.
  const double turned = Eigen::AngleAxisd(total.linear()).angle() * 180.0 / kPi;
  const Vec3 moved_point = total.inverse() * impl_->centroid;
  const double moved = (moved_point - impl_->centroid).norm();
  result.aligned = result.inlier_share >= o.min_inlier_share && moved <= o.max_translation_m &&
                   turned <= o.max_rotation_deg;
  return result;
}

}  // namespace objmap::pose
