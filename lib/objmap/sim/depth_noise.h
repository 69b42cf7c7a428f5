#pragma once
#include <opencv2/core.hpp>

#include "objmap/core/camera.h"
#include "objmap/sim/random.h"

// A Kinect-like depth model applied to an exact depth image.
namespace objmap::sim {

struct DepthNoiseOptions {
  bool enabled = true;  // false: exact depth (only the 16-bit rounding of the PNG remains)
  // Axial noise sigma(z) = sigma_base_m + sigma_quadratic * (z - sigma_ref_z_m)^2 (Nguyen et al.
  // 2012).
  double sigma_base_m = 0.0012;
  double sigma_quadratic = 0.0019;  // 1/m
  double sigma_ref_z_m = 0.4;
  // Disparity quantisation: z is rounded to the nearest disparity step of a structured-light
  // sensor, disparity = fx * baseline / z in pixels. 0 disables it. Steps are ~3 mm at 1 m, ~13 mm
  // at 2 m.
  double disparity_step_px = 0.125;  // Kinect: 1/8 pixel
  double baseline_m = 0.075;         // Kinect projector-camera baseline
  // Range: no depth closer than min_range_m or farther than max_range_m.
  double min_range_m = 0.4;
  double max_range_m = 4.5;
  // Missing depth at depth edges: a pixel within edge_width_px of a neighbour whose exact depth
  // differs by more than edge_jump_m is dropped with probability edge_missing_prob.
  double edge_jump_m = 0.05;
  int edge_width_px = 1;
  double edge_missing_prob = 0.7;
  double dropout_prob = 0.002;  // isolated missing pixels anywhere

  void check() const;               // throws InputError naming the bad field
  static DepthNoiseOptions none();  // everything off
};

// sigma(z) of the model (metres).
double depth_sigma_m(double depth_m, const DepthNoiseOptions& options);

// True where the exact depth has a jump to a neighbour within edge_width_px (CV_8UC1, 0/1).
cv::Mat depth_edges(const cv::Mat& depth_m, const DepthNoiseOptions& options);

// Noisy depth (CV_32FC1, metres, 0 = missing) from exact depth (CV_32FC1). Draws from `rng` in
// pixel order, so the result is a function of the input and the generator state.
cv::Mat apply_depth_noise(const cv::Mat& depth_m, const Camera& camera,
                          const DepthNoiseOptions& options, Rng& rng);

// The 16-bit image that a TUM depth PNG holds: round(depth_m * depth_factor), 0 = missing.
cv::Mat depth_to_u16(const cv::Mat& depth_m, double depth_factor);

}  // namespace objmap::sim
