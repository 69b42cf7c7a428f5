#include "objmap/sim/depth_noise.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "objmap/core/error.h"
#include "objmap/sim/text.h"

namespace objmap::sim {

namespace {
bool nonneg(double v) { return std::isfinite(v) && v >= 0.0; }
bool probability(double p) { return std::isfinite(p) && p >= 0.0 && p <= 1.0; }

// std::round (halves away from zero) without the library call, for x >= 0: x - trunc(x) is exact
// for x < 2^52. Larger values, negative values and NaN go to std::round.
inline double round_nonneg(double x) {
  if (!(x >= 0.0 && x < 4503599627370496.0)) return std::round(x);
  const double t = static_cast<double>(static_cast<std::int64_t>(x));
  return t + static_cast<double>(x - t >= 0.5);  // no branch: the fraction is random
}
}  // namespace

void DepthNoiseOptions::check() const {
  require(nonneg(sigma_base_m), "--depth-sigma-base",
          "must be >= 0 metres, got " + num(sigma_base_m));
  require(nonneg(sigma_quadratic), "--depth-sigma-quadratic",
          "must be >= 0 per metre, got " + num(sigma_quadratic));
  require(nonneg(sigma_ref_z_m), "DepthNoiseOptions.sigma_ref_z_m",
          "must be >= 0, got " + num(sigma_ref_z_m));
  require(nonneg(disparity_step_px), "--disparity-step",
          "must be >= 0 pixels (0 = no quantisation), got " + num(disparity_step_px));
  require(std::isfinite(baseline_m) && baseline_m > 0.0, "DepthNoiseOptions.baseline_m",
          "must be > 0, got " + num(baseline_m));
  require(nonneg(min_range_m) && std::isfinite(max_range_m) && max_range_m > min_range_m,
          "--max-range",
          "range must satisfy 0 <= min < max, got min " + num(min_range_m) + " max " +
              num(max_range_m));
  require(nonneg(edge_jump_m), "DepthNoiseOptions.edge_jump_m",
          "must be >= 0, got " + num(edge_jump_m));
  require(edge_width_px >= 0 && edge_width_px <= 10, "DepthNoiseOptions.edge_width_px",
          "must be in [0, 10], got " + std::to_string(edge_width_px));
  require(probability(edge_missing_prob), "--edge-missing",
          "must be a probability in [0, 1], got " + num(edge_missing_prob));
  require(probability(dropout_prob), "--depth-dropout",
          "must be a probability in [0, 1], got " + num(dropout_prob));
}

DepthNoiseOptions DepthNoiseOptions::none() {
  DepthNoiseOptions o;
  o.enabled = false;
  o.sigma_base_m = 0.0;
  o.sigma_quadratic = 0.0;
  o.disparity_step_px = 0.0;
  o.min_range_m = 0.0;
  o.max_range_m = 1e3;
  o.edge_missing_prob = 0.0;
  o.dropout_prob = 0.0;
  return o;
}

double depth_sigma_m(double z, const DepthNoiseOptions& o) {
  const double dz = z - o.sigma_ref_z_m;
  return o.sigma_base_m + o.sigma_quadratic * dz * dz;
}

cv::Mat depth_edges(const cv::Mat& depth_m, const DepthNoiseOptions& o) {
  cv::Mat edges(depth_m.size(), CV_8UC1, cv::Scalar::all(0));
  const int w = o.edge_width_px;
  if (w <= 0) return edges;
  // A pixel is an edge when a neighbour within the (2w+1)^2 window (clipped at the border) has a
  // surface and it has none, or the other way round, or when |z_n - z| > edge_jump_m for a
  // neighbour. Float subtraction is monotonic, so the largest |z_n - z| is max(z_n) - z or
  // z - min(z_n): window minimum, maximum and count of empty pixels, each separable.
  const int rows = depth_m.rows, cols = depth_m.cols;
  cv::Mat row_min(depth_m.size(), CV_32FC1), row_max(depth_m.size(), CV_32FC1);
  cv::Mat row_empty(depth_m.size(), CV_32SC1);
  for (int v = 0; v < rows; ++v) {
    const float* z = depth_m.ptr<float>(v);
    float* mn = row_min.ptr<float>(v);
    float* mx = row_max.ptr<float>(v);
    int* empty = row_empty.ptr<int>(v);
    for (int u = 0; u < cols; ++u) {
      float lo = z[u], hi = z[u];
      int n = 0;
      for (int uu = std::max(0, u - w); uu <= std::min(cols - 1, u + w); ++uu) {
        lo = std::min(lo, z[uu]);
        hi = std::max(hi, z[uu]);
        n += z[uu] <= 0.0f ? 1 : 0;
      }
      mn[u] = lo;
      mx[u] = hi;
      empty[u] = n;
    }
  }
  for (int v = 0; v < rows; ++v) {
    const int v0 = std::max(0, v - w), v1 = std::min(rows - 1, v + w);
    const int window_rows = v1 - v0 + 1;
    const float* z = depth_m.ptr<float>(v);
    auto* out = edges.ptr<std::uint8_t>(v);
    for (int u = 0; u < cols; ++u) {
      float lo = z[u], hi = z[u];
      int n = 0;
      for (int vv = v0; vv <= v1; ++vv) {
        lo = std::min(lo, row_min.ptr<float>(vv)[u]);
        hi = std::max(hi, row_max.ptr<float>(vv)[u]);
        n += row_empty.ptr<int>(vv)[u];
      }
      const int window = window_rows * (std::min(cols - 1, u + w) - std::max(0, u - w) + 1);
      // When no neighbour differs in having a surface, lo and hi are over pixels of one kind.
      const bool mixed = z[u] <= 0.0f ? n < window : n > 0;
      out[u] = mixed || (hi - z[u]) > o.edge_jump_m || (z[u] - lo) > o.edge_jump_m ? 1 : 0;
    }
  }
  return edges;
}

cv::Mat apply_depth_noise(const cv::Mat& depth_m, const Camera& camera, const DepthNoiseOptions& o,
                          Rng& rng) {
  require(depth_m.type() == CV_32FC1, "apply_depth_noise", "expected a CV_32FC1 depth image");
  if (!o.enabled) return depth_m.clone();
  const cv::Mat edges = o.edge_missing_prob > 0.0 ? depth_edges(depth_m, o) : cv::Mat();
  const double focal_baseline = camera.fx * o.baseline_m;  // pixels * metres
  cv::Mat noisy(depth_m.size(), CV_32FC1, cv::Scalar::all(0));
  for (int v = 0; v < depth_m.rows; ++v) {
    const float* in = depth_m.ptr<float>(v);
    float* out = noisy.ptr<float>(v);
    for (int u = 0; u < depth_m.cols; ++u) {
      const double z = in[u];
      // Draw the same number of numbers for every pixel so that one knob does not shift the others.
      const double gauss = rng.normal();
      const double drop = rng.uniform();
      const double edge_draw = rng.uniform();
      if (z <= 0.0) continue;
      if (z < o.min_range_m || z > o.max_range_m) continue;
      if (drop < o.dropout_prob) continue;
      if (!edges.empty() && edges.at<std::uint8_t>(v, u) && edge_draw < o.edge_missing_prob)
        continue;
      double zn = z + depth_sigma_m(z, o) * gauss;
      if (o.disparity_step_px > 0.0 && zn > 0.0) {
        const double disparity = focal_baseline / zn;
        const double quantised =
            round_nonneg(disparity / o.disparity_step_px) * o.disparity_step_px;
        zn = quantised > 0.0 ? focal_baseline / quantised : 0.0;
      }
      out[u] = zn > 0.0 ? static_cast<float>(zn) : 0.0f;
    }
  }
  return noisy;
}

cv::Mat depth_to_u16(const cv::Mat& depth_m, double depth_factor) {
  cv::Mat out(depth_m.size(), CV_16UC1, cv::Scalar::all(0));
  for (int v = 0; v < depth_m.rows; ++v) {
    const float* in = depth_m.ptr<float>(v);
    auto* o = out.ptr<std::uint16_t>(v);
    for (int u = 0; u < depth_m.cols; ++u) {
      const double d = round_nonneg(static_cast<double>(in[u]) * depth_factor);
      o[u] =
          (d <= 0.0 || d > 65535.0) ? 0 : static_cast<std::uint16_t>(d);  // out of range: missing
    }
  }
  return out;
}

}  // namespace objmap::sim
