#pragma once
#include <cstdint>
#include <vector>

#include "objmap/core/trajectory.h"
#include "objmap/core/types.h"

// Camera paths: an orbit around the table(s) with hand-held jitter (the ground truth), and a
// drifting copy of it that looks like a SLAM estimate.
namespace objmap::sim {

// A place on a walk: where the camera is and what it looks at (world frame).
struct Waypoint {
  Vec3 eye_world = Vec3::Zero();
  Vec3 target_world = Vec3::UnitX();
};

struct CameraPathOptions {
  Vec3 orbit_center_world = Vec3(0.0, 0.0, 0.0);  // the camera circles this vertical axis
  double radius_m = 1.6;                          // distance from the axis
  double height_m = 1.45;                         // camera height above the floor (z = 0)
  double look_at_height_m = 0.78;                 // the camera looks at the axis at this height
  double start_angle_deg = -90.0;       // azimuth of the first frame (-90: on the -y side)
  double speed_deg_per_s = 20.0;        // azimuth rate: 0.56 m/s at 1.6 m (TUM fr1_desk: ~0.4 m/s)
  double jitter_translation_m = 0.004;  // hand-held shake: std of the position offset per axis
  double jitter_rotation_deg = 0.3;     // hand-held shake: std of the orientation offset per axis
  // A walk instead of the orbit where not empty: the camera goes along the waypoints' eyes (a
  // closed loop: after the last, back to the first, and round again) at walk_speed_m_per_s, its
  // target moving between theirs with it.
  std::vector<Waypoint> waypoints;
  double walk_speed_m_per_s = 0.7;
  void check() const;  // throws InputError naming the bad field
};

// Look-at pose in the TUM/optical convention (x right, y down, z forward), world z up.
Pose look_at(const Vec3& eye_world, const Vec3& target_world);

// One pose per timestamp (world_from_cam). The jitter is a sum of sinusoids with random phases and
// frequencies (0.4-2.5 Hz) drawn from `seed`, so it is smooth like a hand.
Trajectory make_camera_path(const CameraPathOptions& options, const std::vector<double>& timestamps,
                            std::uint64_t seed);

// SLAM-like drift: a random-walk bias in translation and in yaw that grows with the distance
// travelled. The end point is off by exactly translation_fraction of the path length (before the
// white noise), the yaw's share included (the yaw drift is scaled down when it alone would move the
// end point by more than 70% of that).
struct DriftOptions {
  double translation_fraction = 0.02;  // |end position error| / path length (0 = no drift)
  double yaw_deg_per_m = 1.0;          // std of the yaw drift rate, degrees per metre travelled
  double random_walk = 0.5;            // share of the translation drift that wanders (0 = straight)
  double white_noise_m = 0.001;        // per-pose position noise on top (std per axis)
  void check() const;
};

double path_length_m(const Trajectory& trajectory);

// The estimate: est_i = D_i * gt_i, with D_0 = identity; the rotation part of D_i is a yaw about
// the first camera position.
Trajectory add_drift(const Trajectory& groundtruth, const DriftOptions& options,
                     std::uint64_t seed);

}  // namespace objmap::sim
