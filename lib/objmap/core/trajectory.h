#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include "objmap/core/types.h"

namespace objmap {

// One pose of a trajectory: time in seconds and the camera pose in the world (TUM convention:
// `t tx ty tz qx qy qz qw` is world_from_cam).
struct StampedPose {
  double timestamp = 0.0;
  Pose world_from_cam = Pose::Identity();
  std::size_t line = 0;  // its line in the file it was read from (0: not read from a file)
};

// A trajectory sorted by strictly increasing timestamp (the readers enforce it).
struct Trajectory {
  std::vector<StampedPose> poses;
  std::string source;  // file it came from, for messages
  // What the reader accepted but a user should know, one line each ("<file>:<line>: ...").
  std::vector<std::string> warnings;

  std::size_t size() const { return poses.size(); }
  bool empty() const { return poses.empty(); }
};

}  // namespace objmap
