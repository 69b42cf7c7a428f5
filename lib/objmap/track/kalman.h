#pragma once
#include <vector>

#include <Eigen/Core>

#include "objmap/segmentation/types.h"

// The constant-velocity Kalman filter of DeepSORT (Wojke et al. 2017, eqs 1-2 of the paper) on an
// image box. State x = (cx, cy, a, h, vcx, vcy, va, vh): box centre in pixels, aspect ratio
// a = w / h, height h in pixels, and their velocities per frame. The measurement is (cx, cy, a, h).
// Process and measurement noise scale with the box height, as in deep_sort/kalman_filter.py.
namespace objmap::track {

using BoxMeasurement = Eigen::Matrix<double, 4, 1>;  // (cx, cy, a, h)
using BoxState = Eigen::Matrix<double, 8, 1>;        // (cx, cy, a, h, vcx, vcy, va, vh)
using BoxStateCov = Eigen::Matrix<double, 8, 8>;

// (cx, cy, w/h, h) of a box (x, y, w, h); h must be > 0.
BoxMeasurement to_measurement(const segmentation::Box& box);
// The box (x, y, w, h) of the first four state entries.
segmentation::Box to_box(const BoxState& mean);

// 0.95 quantile of the chi-square distribution with 4 degrees of freedom: the Mahalanobis gate of
// a (cx, cy, a, h) measurement (DeepSORT's chi2inv95[4]).
constexpr double kChi2Inv95Dof4 = 9.4877;

struct KalmanOptions {
  double std_weight_position = 1.0 / 20;   // position noise std = this x box height (DeepSORT)
  double std_weight_velocity = 1.0 / 160;  // velocity noise std = this x box height (DeepSORT)
  void check() const;                      // throws InputError naming the bad field
};

struct Gaussian {
  BoxState mean = BoxState::Zero();
  BoxStateCov covariance = BoxStateCov::Identity();
};

class KalmanFilter {
 public:
  explicit KalmanFilter(const KalmanOptions& options = {});

  // A new track from an unassociated measurement: zero velocity, height-scaled uncertainty.
  Gaussian initiate(const BoxMeasurement& measurement) const;
  // One frame of constant-velocity motion: x' = F x, P' = F P F^T + Q.
  void predict(Gaussian& state) const;
  // The state in measurement space: (H x, H P H^T + R).
  void project(const Gaussian& state, BoxMeasurement& mean, Eigen::Matrix4d& covariance) const;
  // The Kalman correction with one measurement.
  void update(Gaussian& state, const BoxMeasurement& measurement) const;
  // Squared Mahalanobis distance of each measurement to the projected state (DeepSORT eq 1);
  // compare with kChi2Inv95Dof4. only_position: (cx, cy) only (2 dof).
  std::vector<double> gating_distance(const Gaussian& state,
                                      const std::vector<BoxMeasurement>& measurements,
                                      bool only_position = false) const;

 private:
  KalmanOptions options_;
  Eigen::Matrix<double, 8, 8> motion_;      // F
  Eigen::Matrix<double, 4, 8> projection_;  // H
};

}  // namespace objmap::track
