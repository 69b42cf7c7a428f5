#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "objmap/core/error.h"
#include "objmap/sim/depth_noise.h"
#include "objmap/sim/random.h"
#include "objmap/sim/synth.h"

namespace objmap::sim {
namespace {

struct Stats {
  double mean = 0, std = 0;
  int valid = 0;
};

Stats stats_of(const cv::Mat& noisy, double z) {
  Stats s;
  double sum = 0, sum2 = 0;
  for (int v = 0; v < noisy.rows; ++v)
    for (int u = 0; u < noisy.cols; ++u) {
      const float d = noisy.at<float>(v, u);
      if (d <= 0) continue;
      sum += d - z;
      sum2 += (d - z) * (d - z);
      ++s.valid;
    }
  s.mean = sum / s.valid;
  s.std = std::sqrt(sum2 / s.valid - s.mean * s.mean);
  return s;
}

TEST(DepthNoise, SigmaGrowsWithDepthAsTheModelSays) {
  DepthNoiseOptions o;
  o.disparity_step_px = 0.0;  // Gaussian part only
  o.edge_missing_prob = 0.0;
  o.dropout_prob = 0.0;
  const Camera cam = synthetic_camera();
  for (double z : {1.0, 3.0}) {
    const cv::Mat exact(200, 200, CV_32FC1, cv::Scalar(z));
    Rng rng(42);
    const Stats s = stats_of(apply_depth_noise(exact, cam, o, rng), z);
    const double sigma = 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4);
    EXPECT_NEAR(depth_sigma_m(z, o), sigma, 1e-15);
    EXPECT_EQ(s.valid, 200 * 200);
    EXPECT_NEAR(s.std, sigma, 0.03 * sigma) << "z " << z;
    EXPECT_NEAR(s.mean, 0.0, 4.0 * sigma / 200.0) << "z " << z;
  }
  // At 1 m: 1.88 mm; at 3 m: 14.0 mm.
  EXPECT_NEAR(depth_sigma_m(3.0, o), 0.014044, 1e-6);
}

TEST(DepthNoise, QuantisationGivesDisparityLevels) {
  DepthNoiseOptions o;
  o.edge_missing_prob = 0.0;
  o.dropout_prob = 0.0;
  const Camera cam = synthetic_camera();
  const double z = 2.0;
  const cv::Mat exact(100, 100, CV_32FC1, cv::Scalar(z));
  Rng rng(1);
  const cv::Mat noisy = apply_depth_noise(exact, cam, o, rng);
  std::set<float> levels;
  for (int v = 0; v < noisy.rows; ++v)
    for (int u = 0; u < noisy.cols; ++u) levels.insert(noisy.at<float>(v, u));
  // sigma(2 m) = 6.1 mm and the step at 2 m is z^2 * step / (fx * b) = 12.9 mm: a handful of
  // levels.
  EXPECT_GE(levels.size(), 2u);
  EXPECT_LE(levels.size(), 8u);
  const double step = z * z * o.disparity_step_px / (cam.fx * o.baseline_m);
  std::vector<float> sorted(levels.begin(), levels.end());
  for (std::size_t i = 1; i < sorted.size(); ++i) {
    const double mid = 0.5 * (sorted[i] + sorted[i - 1]);
    EXPECT_NEAR(sorted[i] - sorted[i - 1],
                mid * mid * o.disparity_step_px / (cam.fx * o.baseline_m), 1e-5);
  }
  EXPECT_NEAR(step, 0.0129, 0.0005);
}

TEST(DepthNoise, MissingAtDepthEdgesAndBeyondRange) {
  DepthNoiseOptions o;
  o.dropout_prob = 0.0;
  o.edge_missing_prob = 1.0;
  const Camera cam = synthetic_camera();
  cv::Mat exact(50, 100, CV_32FC1, cv::Scalar(1.0));
  exact.colRange(50, 100).setTo(2.0);
  exact.colRange(90, 100).setTo(5.0);  // beyond 4.5 m
  Rng rng(3);
  const cv::Mat noisy = apply_depth_noise(exact, cam, o, rng);
  for (int v = 0; v < 50; ++v) {
    EXPECT_EQ(noisy.at<float>(v, 49), 0.0f);  // both sides of the 1 m / 2 m edge
    EXPECT_EQ(noisy.at<float>(v, 50), 0.0f);
    EXPECT_GT(noisy.at<float>(v, 20), 0.0f);  // away from the edge: depth
    EXPECT_GT(noisy.at<float>(v, 70), 0.0f);
    EXPECT_EQ(noisy.at<float>(v, 95), 0.0f);  // beyond range
  }
  // Noise-free: exact values, even beyond the range.
  Rng rng2(3);
  const cv::Mat exact_out = apply_depth_noise(exact, cam, DepthNoiseOptions::none(), rng2);
  EXPECT_EQ(cv::norm(exact_out, exact, cv::NORM_INF), 0.0);
}

TEST(DepthNoise, RenderedFrameLosesDepthAtObjectSilhouettes) {
  SynthOptions options;
  options.frames = 1;
  options.resolution_scale = 0.5;
  const SynthSequence seq = synthesize(options);
  const SynthFrame& f = seq.frames[0];
  const cv::Mat edges = depth_edges(f.depth_exact_m, options.depth_noise);
  int edge = 0, edge_missing = 0, flat = 0, flat_missing = 0;
  for (int v = 0; v < edges.rows; ++v)
    for (int u = 0; u < edges.cols; ++u) {
      const double z = f.depth_exact_m.at<float>(v, u);
      if (z > options.depth_noise.max_range_m || z < options.depth_noise.min_range_m) continue;
      const bool missing = f.depth.at<std::uint16_t>(v, u) == 0;
      if (edges.at<std::uint8_t>(v, u)) {
        ++edge;
        edge_missing += missing;
      } else {
        ++flat;
        flat_missing += missing;
      }
    }
  ASSERT_GT(edge, 200);
  EXPECT_NEAR(static_cast<double>(edge_missing) / edge, options.depth_noise.edge_missing_prob, 0.1);
  EXPECT_LT(static_cast<double>(flat_missing) / flat, 0.01);
}

// The definition depth_edges() implements with separable window minima and maxima: a neighbour in
// the window with a surface where the pixel has none (or the reverse), or a depth jump.
cv::Mat brute_force_edges(const cv::Mat& depth_m, const DepthNoiseOptions& o) {
  cv::Mat edges(depth_m.size(), CV_8UC1, cv::Scalar::all(0));
  const int w = o.edge_width_px;
  for (int v = 0; v < depth_m.rows; ++v)
    for (int u = 0; u < depth_m.cols; ++u) {
      const float z = depth_m.at<float>(v, u);
      for (int vv = std::max(0, v - w); vv <= std::min(depth_m.rows - 1, v + w); ++vv)
        for (int uu = std::max(0, u - w); uu <= std::min(depth_m.cols - 1, u + w); ++uu) {
          const float zn = depth_m.at<float>(vv, uu);
          if ((zn <= 0.0f) != (z <= 0.0f) || std::abs(zn - z) > o.edge_jump_m)
            edges.at<std::uint8_t>(v, u) = 1;
        }
    }
  return edges;
}

TEST(DepthNoise, EdgesMatchTheirDefinitionExactly) {
  // Steps just above and below the jump threshold, holes, negative values, image borders.
  cv::Mat depth(37, 53, CV_32FC1);
  Rng rng(7);
  for (int v = 0; v < depth.rows; ++v)
    for (int u = 0; u < depth.cols; ++u) {
      const double r = rng.uniform();
      depth.at<float>(v, u) = r < 0.08  ? 0.0f
                              : r < 0.1 ? -0.5f
                              : r < 0.4
                                  ? static_cast<float>(1.0 + 0.049 * rng.uniform())
                                  : static_cast<float>(1.0 + 0.1 * (u / 10) + 0.0501 * (v / 9));
    }
  for (int w : {0, 1, 2, 3}) {
    DepthNoiseOptions o;
    o.edge_width_px = w;
    const cv::Mat fast = depth_edges(depth, o), slow = brute_force_edges(depth, o);
    EXPECT_EQ(cv::countNonZero(fast != slow), 0) << "edge width " << w;
    if (w > 0) {
      EXPECT_GT(cv::countNonZero(slow), 100);
    }
  }
}

TEST(DepthNoise, BadOptionsNameTheKnob) {
  DepthNoiseOptions o;
  o.edge_missing_prob = 1.5;
  try {
    o.check();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "--edge-missing");
  }
}

}  // namespace
}  // namespace objmap::sim
