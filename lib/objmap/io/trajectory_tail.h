#pragma once
#include <cstddef>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "objmap/core/trajectory.h"

// A TUM trajectory file that grows while it is read (a SLAM system writing its poses as it goes,
// objmap follow): read again at each poll, tolerantly. The last line without its '\n' is still
// being written and is left for the next poll; a complete line that is malformed (not 8 finite
// numbers, a quaternion off unit, a timestamp not after the previous pose's) is named
// (<file>:<line>), skipped and counted, once; a past line that changed (a loop closure that
// rewrote the file) is reported as a rewrite.
namespace objmap::io {

struct TrajectoryTailPoll {
  std::size_t new_poses = 0;           // poses after the ones of the last poll
  bool rewritten = false;              // a pose of the last poll changed or went away
  std::vector<std::string> malformed;  // "<file>:<line>: <reason>; skipped", new ones only
};

class TrajectoryTail {
 public:
  explicit TrajectoryTail(std::filesystem::path file);

  // Reads the file again (a file not there yet has no pose). Throws nothing for its contents.
  TrajectoryTailPoll poll();

  const Trajectory& trajectory() const { return trajectory_; }
  std::size_t lines() const { return lines_; }                // complete data lines read
  std::size_t malformed() const { return reported_.size(); }  // malformed lines, all polls
  std::size_t rewrites() const { return rewrites_; }          // polls that saw a rewrite

 private:
  std::filesystem::path file_;
  Trajectory trajectory_;
  std::size_t lines_ = 0;
  std::set<std::size_t> reported_;  // line numbers named so far
  std::size_t rewrites_ = 0;
};

}  // namespace objmap::io
