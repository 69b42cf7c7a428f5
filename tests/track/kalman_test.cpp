// DeepSORT's Kalman filter: noise scaled with the box height, constant-velocity tracking, gating.
#include <gtest/gtest.h>

#include "objmap/core/error.h"
#include "objmap/track/kalman.h"

namespace objmap::track {
namespace {

TEST(Kalman, MeasurementRoundTrip) {
  const segmentation::Box box{10, 20, 30, 60};
  const BoxMeasurement z = to_measurement(box);
  EXPECT_DOUBLE_EQ(z(0), 25);
  EXPECT_DOUBLE_EQ(z(1), 50);
  EXPECT_DOUBLE_EQ(z(2), 0.5);
  EXPECT_DOUBLE_EQ(z(3), 60);
  BoxState x = BoxState::Zero();
  x.head<4>() = z;
  const segmentation::Box back = to_box(x);
  EXPECT_DOUBLE_EQ(back.x, 10);
  EXPECT_DOUBLE_EQ(back.y, 20);
  EXPECT_DOUBLE_EQ(back.w, 30);
  EXPECT_DOUBLE_EQ(back.h, 60);
}

// deep_sort's initiate: position std 2 x (1/20) x h, velocity std 10 x (1/160) x h.
TEST(Kalman, InitialCovarianceScalesWithHeight) {
  const KalmanFilter kf;
  const Gaussian g = kf.initiate(to_measurement({0, 0, 50, 100}));
  EXPECT_DOUBLE_EQ(g.covariance(0, 0), (2 * 100.0 / 20) * (2 * 100.0 / 20));
  EXPECT_DOUBLE_EQ(g.covariance(2, 2), 1e-4);
  EXPECT_DOUBLE_EQ(g.covariance(4, 4), (10 * 100.0 / 160) * (10 * 100.0 / 160));
  EXPECT_DOUBLE_EQ(g.mean(4), 0.0);
}

// A box moving at 3 px/frame: after some updates the velocity estimate is 3 and the prediction
// lands on the next measurement.
TEST(Kalman, LearnsConstantVelocity) {
  const KalmanFilter kf;
  Gaussian g = kf.initiate(to_measurement({0, 100, 40, 80}));
  for (int k = 1; k <= 30; ++k) {
    kf.predict(g);
    kf.update(g, to_measurement({3.0 * k, 100, 40, 80}));
  }
  EXPECT_NEAR(g.mean(4), 3.0, 0.05);
  EXPECT_NEAR(g.mean(5), 0.0, 0.05);
  kf.predict(g);
  EXPECT_NEAR(g.mean(0), 3.0 * 31 + 20, 0.5);
  // Gate: the predicted next box is well inside, a box 60 px away is outside.
  const auto d = kf.gating_distance(
      g, {to_measurement({3.0 * 31, 100, 40, 80}), to_measurement({3.0 * 31 + 60, 100, 40, 80})});
  EXPECT_LT(d[0], 1.0);
  EXPECT_GT(d[1], kChi2Inv95Dof4);
}

TEST(Kalman, BadOptionsAreNamed) {
  KalmanOptions o;
  o.std_weight_velocity = 0;
  try {
    o.check();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "KalmanOptions.std_weight_velocity");
  }
}

}  // namespace
}  // namespace objmap::track
