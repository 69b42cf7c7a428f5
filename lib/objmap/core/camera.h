#pragma once
#include <array>
#include <string>

#include "objmap/core/types.h"

namespace objmap {

// A pinhole RGB-D camera with Brown-Conrady distortion (OpenCV order k1 k2 p1 p2 k3, which is TUM's
// d0..d4). Depth images hold `depth_m * depth_factor` as 16-bit integers.
struct Camera {
  std::string name = "custom";  // preset name ("fr1"...) or the file it came from
  int width = 640;
  int height = 480;
  double fx = 525.0;
  double fy = 525.0;
  double cx = 319.5;
  double cy = 239.5;
  std::array<double, 5> distortion{};  // k1 k2 p1 p2 k3; all zero = no distortion
  double depth_factor = 5000.0;        // TUM: 5000; YCB-Video: 10000

  bool has_distortion() const;
  // Throws InputError naming the bad field (`where` names the source, e.g. the file).
  void check(const std::string& where = "camera") const;

  // Normalised image coordinates (x/z, y/z) of pixel (u, v), distortion removed (iterative
  // inverse).
  Eigen::Vector2d undistort_pixel(double u, double v) const;
  // point_in_cam for pixel (u, v) at depth `depth_m` (z along the optical axis), eqs 11-15.
  Vec3 unproject(double u, double v, double depth_m) const;
  // Pixel of a point in the camera frame (distortion applied). z must be > 0.
  Eigen::Vector2d project(const Vec3& point_in_cam) const;
};

// TUM RGB-D presets: "fr1", "fr2", "fr3" (also "freiburg1".."freiburg3"), intrinsics and distortion
// as published by the benchmark. Throws InputError for another name.
Camera camera_preset(const std::string& name);

}  // namespace objmap
