#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

// Plain value types shared by every stage. No PCL, no OpenCV here.
namespace objmap {

using Vec3 = Eigen::Vector3d;
using Vec3f = Eigen::Vector3f;
// A rigid transform named by its frames: `world_from_cam * point_in_cam = point_in_world`.
using Pose = Eigen::Isometry3d;

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb& o) const { return r == o.r && g == o.g && b == o.b; }
};

// A point cloud as two parallel arrays (structure of arrays): positions in metres and, optionally,
// colours. `colors` is either empty or exactly as long as `points`.
struct PointCloud {
  std::vector<Vec3f> points;
  std::vector<Rgb> colors;

  std::size_t size() const { return points.size(); }
  bool empty() const { return points.empty(); }
  bool has_colors() const { return !colors.empty() && colors.size() == points.size(); }
  void reserve(std::size_t n) {
    points.reserve(n);
    colors.reserve(n);
  }
  void push_back(const Vec3f& p) { points.push_back(p); }
  void push_back(const Vec3f& p, Rgb c) {
    points.push_back(p);
    colors.push_back(c);
  }
  void clear() {
    points.clear();
    colors.clear();
  }
};

// Axis-aligned box in the world frame.
struct Aabb {
  Vec3 min = Vec3::Zero();
  Vec3 max = Vec3::Zero();
};

// Oriented box: `rotation` columns are the box axes in the world frame, `half_extent` along them.
struct Obb {
  Vec3 center = Vec3::Zero();
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Vec3 half_extent = Vec3::Zero();
  // True when `point_in_world` lies inside the box grown by `margin` metres on every side.
  bool contains(const Vec3& point_in_world, double margin = 0.0) const;
};

}  // namespace objmap
