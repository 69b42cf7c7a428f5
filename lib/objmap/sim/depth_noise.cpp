#include "objmap/sim/depth_noise.h"

#include <cmath>
#include <string>

#include "objmap/core/error.h"
#include "objmap/sim/text.h"

namespace objmap::sim {

namespace {
bool nonneg(double v) { return std::isfinite(v) && v >= 0.0; }
bool probability(double p) { return std::isfinite(p) && p >= 0.0 && p <= 1.0; }
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
  for (int v = 0; v < depth_m.rows; ++v) {
    for (int u = 0; u < depth_m.cols; ++u) {
      const float z = depth_m.at<float>(v, u);
      bool edge = false;
      for (int dv = -w; dv <= w && !edge; ++dv) {
        const int vv = v + dv;
        if (vv < 0 || vv >= depth_m.rows) continue;
        const float* row = depth_m.ptr<float>(vv);
        for (int du = -w; du <= w; ++du) {
          const int uu = u + du;
          if (uu < 0 || uu >= depth_m.cols) continue;
          const float zn = row[uu];
          // A neighbour with no surface counts as a jump (silhouette against nothing).
          if ((zn <= 0.0f) != (z <= 0.0f) || std::abs(zn - z) > o.edge_jump_m) {
            edge = true;
            break;
          }
        }
      }
      edges.at<std::uint8_t>(v, u) = edge ? 1 : 0;
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
        const double quantised = std::round(disparity / o.disparity_step_px) * o.disparity_step_px;
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
      const double d = std::round(static_cast<double>(in[u]) * depth_factor);
      o[u] =
          (d <= 0.0 || d > 65535.0) ? 0 : static_cast<std::uint16_t>(d);  // out of range: missing
    }
  }
  return out;
}

}  // namespace objmap::sim
