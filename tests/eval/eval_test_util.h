#pragma once
// Small constructed trajectories for the eval tests.
#include <cmath>
#include <vector>

#include "objmap/core/trajectory.h"

namespace objmap::eval::test {

constexpr double kPi = 3.14159265358979323846;

inline Pose make_pose(const Eigen::Matrix3d& rotation, const Vec3& translation) {
  Pose pose = Pose::Identity();
  pose.linear() = rotation;
  pose.translation() = translation;
  return pose;
}

inline Eigen::Matrix3d rot_z(double angle_rad) {
  return Eigen::AngleAxisd(angle_rad, Vec3::UnitZ()).toRotationMatrix();
}

inline Trajectory make_trajectory(const std::vector<double>& stamps, const std::vector<Pose>& poses,
                                  const std::string& source = "") {
  Trajectory t;
  t.source = source;
  for (std::size_t i = 0; i < stamps.size(); ++i) t.poses.push_back({stamps[i], poses[i]});
  return t;
}

}  // namespace objmap::eval::test
