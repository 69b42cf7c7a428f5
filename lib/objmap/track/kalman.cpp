#include "objmap/track/kalman.h"

#include <cmath>
#include <string>

#include <Eigen/Cholesky>

#include "objmap/core/error.h"

namespace objmap::track {

BoxMeasurement to_measurement(const segmentation::Box& box) {
  BoxMeasurement z;
  z << box.x + box.w / 2, box.y + box.h / 2, box.w / box.h, box.h;
  return z;
}

segmentation::Box to_box(const BoxState& mean) {
  segmentation::Box box;
  box.h = mean(3);
  box.w = mean(2) * mean(3);
  box.x = mean(0) - box.w / 2;
  box.y = mean(1) - box.h / 2;
  return box;
}

void KalmanOptions::check() const {
  require(std::isfinite(std_weight_position) && std_weight_position > 0,
          "KalmanOptions.std_weight_position",
          "must be > 0, got " + std::to_string(std_weight_position));
  require(std::isfinite(std_weight_velocity) && std_weight_velocity > 0,
          "KalmanOptions.std_weight_velocity",
          "must be > 0, got " + std::to_string(std_weight_velocity));
}

KalmanFilter::KalmanFilter(const KalmanOptions& options) : options_(options) {
  options_.check();
  motion_.setIdentity();
  for (int i = 0; i < 4; ++i) motion_(i, 4 + i) = 1.0;  // dt = one frame
  projection_.setZero();
  for (int i = 0; i < 4; ++i) projection_(i, i) = 1.0;
}

Gaussian KalmanFilter::initiate(const BoxMeasurement& z) const {
  const double h = z(3), wp = options_.std_weight_position, wv = options_.std_weight_velocity;
  Eigen::Matrix<double, 8, 1> std;
  std << 2 * wp * h, 2 * wp * h, 1e-2, 2 * wp * h, 10 * wv * h, 10 * wv * h, 1e-5, 10 * wv * h;
  Gaussian g;
  g.mean.head<4>() = z;
  g.mean.tail<4>().setZero();
  g.covariance = std.array().square().matrix().asDiagonal();
  return g;
}

void KalmanFilter::predict(Gaussian& g) const {
  const double h = g.mean(3), wp = options_.std_weight_position, wv = options_.std_weight_velocity;
  Eigen::Matrix<double, 8, 1> std;
  std << wp * h, wp * h, 1e-2, wp * h, wv * h, wv * h, 1e-5, wv * h;
  const BoxStateCov q = std.array().square().matrix().asDiagonal();
  g.mean = motion_ * g.mean;
  g.covariance = motion_ * g.covariance * motion_.transpose() + q;
}

void KalmanFilter::project(const Gaussian& g, BoxMeasurement& mean,
                           Eigen::Matrix4d& covariance) const {
  const double h = g.mean(3), wp = options_.std_weight_position;
  Eigen::Vector4d std(wp * h, wp * h, 1e-1, wp * h);
  const Eigen::Matrix4d r = std.array().square().matrix().asDiagonal();
  mean = projection_ * g.mean;
  covariance = projection_ * g.covariance * projection_.transpose() + r;
}

void KalmanFilter::update(Gaussian& g, const BoxMeasurement& z) const {
  BoxMeasurement projected_mean;
  Eigen::Matrix4d projected_cov;
  project(g, projected_mean, projected_cov);
  // K = P H^T S^-1, solved with the Cholesky factor of S (symmetric positive definite).
  const Eigen::LLT<Eigen::Matrix4d> llt(projected_cov);
  const Eigen::Matrix<double, 8, 4> pht = g.covariance * projection_.transpose();
  const Eigen::Matrix<double, 8, 4> gain = llt.solve(pht.transpose()).transpose();
  g.mean += gain * (z - projected_mean);
  g.covariance -= gain * projected_cov * gain.transpose();
}

std::vector<double> KalmanFilter::gating_distance(const Gaussian& g,
                                                  const std::vector<BoxMeasurement>& zs,
                                                  bool only_position) const {
  BoxMeasurement mean;
  Eigen::Matrix4d cov;
  project(g, mean, cov);
  std::vector<double> d;
  d.reserve(zs.size());
  if (only_position) {
    const Eigen::LLT<Eigen::Matrix2d> llt(cov.topLeftCorner<2, 2>());
    for (const auto& z : zs) {
      const Eigen::Vector2d e = z.head<2>() - mean.head<2>();
      d.push_back(e.dot(llt.solve(e)));
    }
  } else {
    const Eigen::LLT<Eigen::Matrix4d> llt(cov);
    for (const auto& z : zs) {
      const Eigen::Vector4d e = z - mean;
      d.push_back(e.dot(llt.solve(e)));
    }
  }
  return d;
}

}  // namespace objmap::track
