#include "objmap/core/camera.h"

#include <cmath>

#include "objmap/core/error.h"

namespace objmap {

bool Camera::has_distortion() const {
  for (double d : distortion)
    if (d != 0.0) return true;
  return false;
}

void Camera::check(const std::string& where) const {
  auto finite_positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  require(width > 0 && height > 0, where,
          "image size " + std::to_string(width) + "x" + std::to_string(height) +
              "; expected width and height > 0");
  require(finite_positive(fx) && finite_positive(fy), where,
          "focal length fx/fy must be finite and > 0");
  require(std::isfinite(cx) && std::isfinite(cy), where, "principal point cx/cy must be finite");
  for (double d : distortion) require(std::isfinite(d), where, "distortion must be finite");
  require(finite_positive(depth_factor), where, "depth_factor must be finite and > 0");
}

Eigen::Vector2d Camera::undistort_pixel(double u, double v) const {
  const double xd = (u - cx) / fx;
  const double yd = (v - cy) / fy;
  if (!has_distortion()) return {xd, yd};
  const double k1 = distortion[0], k2 = distortion[1], p1 = distortion[2], p2 = distortion[3],
               k3 = distortion[4];
  // Fixed-point iteration as in OpenCV's cvUndistortPoints, 20 steps. A step is a function of
  // (x, y) alone, so once a step returns its input exactly the remaining steps would too: stopping
  // there gives the same bits, in about half the steps for TUM's fr1/fr2 lenses.
  double x = xd, y = yd;
  for (int i = 0; i < 20; ++i) {
    const double r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    const double dx = 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
    const double dy = p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
    const double nx = (xd - dx) / radial, ny = (yd - dy) / radial;
    if (nx == x && ny == y) break;
    x = nx;
    y = ny;
  }
  return {x, y};
}

Vec3 Camera::unproject(double u, double v, double depth_m) const {
  const Eigen::Vector2d xy = undistort_pixel(u, v);
  return {xy.x() * depth_m, xy.y() * depth_m, depth_m};
}

Eigen::Vector2d Camera::project(const Vec3& point_in_cam) const {
  double x = point_in_cam.x() / point_in_cam.z();
  double y = point_in_cam.y() / point_in_cam.z();
  if (has_distortion()) {
    const double k1 = distortion[0], k2 = distortion[1], p1 = distortion[2], p2 = distortion[3],
                 k3 = distortion[4];
    const double r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    const double xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
    const double yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
    x = xd;
    y = yd;
  }
  return {fx * x + cx, fy * y + cy};
}

Camera camera_preset(const std::string& name) {
  Camera c;
  if (name == "fr1" || name == "freiburg1") {
    c = {"fr1", 640, 480, 517.3, 516.5, 318.6, 255.3, {0.2624, -0.9531, -0.0054, 0.0026, 1.1633},
         5000.0};
  } else if (name == "fr2" || name == "freiburg2") {
    c = {"fr2", 640, 480, 520.9, 521.0, 325.1, 249.7, {0.2312, -0.7849, -0.0033, -0.0001, 0.9172},
         5000.0};
  } else if (name == "fr3" || name == "freiburg3") {
    c = {"fr3", 640, 480, 535.4, 539.2, 320.1, 247.6, {0, 0, 0, 0, 0}, 5000.0};
  } else {
    throw InputError("--camera",
                     "unknown preset '" + name +
                         "'; expected fr1, fr2, fr3, an ORB-SLAM2 .yaml or a .json file");
  }
  return c;
}

}  // namespace objmap
