#pragma once
#include <filesystem>
#include <optional>
#include <string>

#include "objmap/core/trajectory.h"

// Trajectories in the TUM format, one pose per line: `timestamp tx ty tz qx qy qz qw`, the pose
// being world_from_cam (translation in metres, Hamilton quaternion, scalar last). ORB-SLAM2's
// KeyFrameTrajectory.txt and CameraTrajectory.txt, RGBD-SLAM's and the TUM groundtruth.txt are this
// format. Lines starting with '#' and blank lines are skipped; fields may be separated by spaces,
// tabs or commas.
namespace objmap::io {

// Largest accepted |‖q‖ − 1| of a quaternion in a file; within it the quaternion is normalised.
// (TUM's groundtruth, written with 4 decimals, is within 1e-4.)
constexpr double kMaxQuaternionNormError = 1e-3;

// Reads a trajectory. Throws InputError("<file>:<line>", ...) for a line without exactly 8 fields,
// a field that is not a finite number, a quaternion whose norm is off by more than
// kMaxQuaternionNormError, a timestamp before the previous one, and a file with no pose. A
// timestamp equal to the previous one replaces that pose, as the TUM benchmark's evaluate_ate.py
// and associate.py do (they read the file into a dictionary), with a line in `warnings`.
Trajectory read_trajectory(const std::filesystem::path& file);

// Writes `trajectory` in the TUM format, atomically (see atomic.h). `header_comment` (may span
// several lines) is written first with "# " before each line, then "# timestamp tx ty tz qx qy qz
// qw". Numbers are written in the shortest form that reads back to the same double, so timestamps
// and translations survive write -> read bit for bit. The quaternion (unit, qw >= 0) is chosen so
// that reading it back gives the same rotation matrix bit for bit when one is found near the
// matrix's quaternion: measured, every pose of fr1_xyz's groundtruth and RGBD-SLAM files, 96.7-100%
// of the other TUM files' poses; the others come back within 2 ulps (4.4e-16).
void write_trajectory(const std::filesystem::path& file, const Trajectory& trajectory,
                      const std::string& header_comment = "");

// The TUM text of a trajectory (what write_trajectory writes).
std::string format_trajectory(const Trajectory& trajectory, const std::string& header_comment = "");

struct PoseLookupOptions {
  double max_diff_s = 0.02;  // a pose counts when |t_pose - t| <= max_diff_s; finite, >= 0
  bool interpolate = false;  // linear translation + slerp between the two poses bracketing t
  void check() const;        // throws InputError naming the bad field
};

// The pose of `trajectory` at `timestamp`, or nullopt when there is none within max_diff_s.
//  - interpolate = false: the nearest pose (the earlier one on a tie) if within max_diff_s.
//  - interpolate = true: a pose stamped exactly t is returned as is; otherwise, when the poses just
//    before and just after t are BOTH within max_diff_s of t (so their gap is <= 2 max_diff_s), the
//    translation is interpolated linearly and the rotation by slerp; when only one side is within
//    max_diff_s, that nearest pose is returned (no extrapolation).
std::optional<Pose> lookup_pose(const Trajectory& trajectory, double timestamp,
                                const PoseLookupOptions& options);

// Pose conversions used by the reader and writer. pose_from_tum normalises the quaternion (x, y, z,
// w) unless it is unit to double precision, and computes the rotation in extended precision;
// quaternion_of returns a unit quaternion with w >= 0 that pose_from_tum turns back into the same
// rotation matrix when it can find one (see write_trajectory).
Pose pose_from_tum(double tx, double ty, double tz, double qx, double qy, double qz, double qw);
Eigen::Quaterniond quaternion_of(const Pose& pose);

}  // namespace objmap::io
