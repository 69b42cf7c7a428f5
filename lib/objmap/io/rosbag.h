#pragma once
#include <filesystem>

#include "objmap/io/dataset.h"

// The rosbag layout: a ROS 1 bag (what RealSense `.bag` recordings are, and the bags of the TUM
// RGB-D benchmark), read with Debian's rosbag_storage (both chunk compressions, bz2 and lz4). No
// ROS header is included here: the messages stay inside io/rosbag.cpp.
namespace objmap::io {

// The recording in `bag`: one colour and one depth image stream (sensor_msgs/Image or
// CompressedImage, options.topics "COLOR,DEPTH" or chosen from the bag), their camera_info, the
// depth-to-colour transform where depth is not registered, frames paired by their header stamps
// (within options.max_diff_s, as the tum layout). Throws InputError naming the bag, the topic and
// what was expected.
Dataset read_rosbag(const std::filesystem::path& bag, const DatasetOptions& options);

}  // namespace objmap::io
