#include "objmap/io/trajectory_tail.h"

#include <cmath>
#include <fstream>
#include <sstream>
#include <utility>

#include "objmap/core/error.h"
#include "objmap/io/text_lines.h"
#include "objmap/io/trajectory.h"

namespace objmap::io {

namespace fs = std::filesystem;

namespace {

// The complete lines of `file` (up to its last '\n'); empty when it cannot be read.
std::vector<std::string> complete_lines(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return {};
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  std::vector<std::string> lines;
  std::size_t start = 0;
  for (std::size_t end = text.find('\n'); end != std::string::npos;
       start = end + 1, end = text.find('\n', start)) {
    std::string line = text.substr(start, end - start);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(std::move(line));
  }
  return lines;
}

// One data line's fields as a pose; throws InputError(where, reason) when it is malformed.
StampedPose parse_pose_line(const std::vector<std::string>& fields, const std::string& where) {
  require(fields.size() == 8, where,
          std::to_string(fields.size()) + " fields; expected 8: timestamp tx ty tz qx qy qz qw");
  static const char* names[] = {"timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
  double v[8];
  for (int i = 0; i < 8; ++i) v[i] = parse_double(fields[i], where, names[i]);
  const double norm = std::sqrt(v[4] * v[4] + v[5] * v[5] + v[6] * v[6] + v[7] * v[7]);
  require(std::abs(norm - 1.0) <= kMaxQuaternionNormError, where,
          "quaternion norm " + std::to_string(norm) + "; expected 1");
  StampedPose pose;
  pose.timestamp = v[0];
  pose.world_from_cam = pose_from_tum(v[1], v[2], v[3], v[4], v[5], v[6], v[7]);
  return pose;
}

bool same_pose(const StampedPose& a, const StampedPose& b) {
  return a.timestamp == b.timestamp && a.world_from_cam.matrix() == b.world_from_cam.matrix();
}

}  // namespace

TrajectoryTail::TrajectoryTail(fs::path file) : file_(std::move(file)) {
  trajectory_.source = file_.string();
}

TrajectoryTailPoll TrajectoryTail::poll() {
  TrajectoryTailPoll result;
  Trajectory next;
  next.source = file_.string();
  const std::vector<std::string> lines = complete_lines(file_);
  lines_ = 0;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    // Blank lines, comments and lines of separators only (",,,") are skipped as read_trajectory
    // (io/text_lines.cpp, LineReader) skips them, so that a file fuse reads whole is read here
    // without a line named malformed.
    const auto first = lines[i].find_first_not_of(" \t\v\f");
    if (first == std::string::npos || lines[i][first] == '#') continue;
    const std::vector<std::string> fields = split_fields(lines[i]);
    if (fields.empty()) continue;
    ++lines_;
    const std::string where = file_.string() + ":" + std::to_string(i + 1);
    try {
      StampedPose pose = parse_pose_line(fields, where);
      pose.line = i + 1;
      require(next.poses.empty() || pose.timestamp > next.poses.back().timestamp, where,
              "timestamp not after the previous pose's");
      next.poses.push_back(std::move(pose));
    } catch (const InputError& e) {
      if (reported_.insert(i + 1).second)
        result.malformed.push_back(e.what() + std::string("; skipped"));
    }
  }
  const std::size_t before = trajectory_.poses.size();
  for (std::size_t i = 0; i < before && !result.rewritten; ++i)
    result.rewritten = i >= next.poses.size() || !same_pose(trajectory_.poses[i], next.poses[i]);
  if (result.rewritten) ++rewrites_;
  result.new_poses = next.poses.size() > before ? next.poses.size() - before : 0;
  trajectory_ = std::move(next);
  return result;
}

}  // namespace objmap::io
