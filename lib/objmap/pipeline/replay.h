#pragma once
#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>

// `objmap replay`: a finished recording written again into a new folder at its own frame rate, as
// a camera and a SLAM system would write it: the test harness of `objmap follow` and a demo.
// Each frame's files are written under a temporary name and renamed; the listing files (rgb.txt,
// depth.txt) and the trajectory get their lines appended as their frames arrive; DST/done is
// written at the end. With rewrite_at, the trajectory's lines are written with a drift until that
// fraction of the recording, where the whole file is rewritten with the source's poses (a loop
// closure: every earlier pose moves) and the later lines follow the source.
namespace objmap::pipeline {

struct ReplayOptions {
  std::filesystem::path dataset;     // the source recording: tum or 7scenes layout
  std::filesystem::path out;         // new, empty, or an earlier replay (it holds replay.json)
  std::filesystem::path trajectory;  // streamed trajectory; default the source's groundtruth.txt
  double speed = 1.0;                // 2: twice the recording's own rate
  // < 0: no loop closure. In [0, 1]: the trajectory is written drifted (drift_deg about the
  // world's z and drift_m along x, growing linearly from 0 at the first frame to the full amount
  // at this fraction of the frames), then rewritten with the source's poses at this fraction.
  double rewrite_at = -1.0;
  double drift_deg = 3.0;  // the drift's rotation at the rewrite
  double drift_m = 0.10;   // the drift's translation at the rewrite
  void check() const;      // throws InputError naming the bad field
};

struct ReplayResult {
  std::string layout;
  std::size_t frames = 0;            // frames written (their colour image)
  std::size_t files = 0;             // frame files written
  std::size_t trajectory_lines = 0;  // trajectory lines appended (rewrite not counted)
  bool rewritten = false;            // the trajectory was rewritten (rewrite_at)
  double seconds = 0.0;              // wall time of the replay
  double behind_s = 0.0;             // the most an event was written after its time
};

// Called after each frame: frames written so far, frames in all.
using ReplayProgress = std::function<void(std::size_t done, std::size_t total)>;

// Replays the recording. Throws InputError for bad input (a layout it cannot replay, an --out that
// is not replaceable, an unreadable source file).
ReplayResult run_replay(const ReplayOptions& options, const ReplayProgress& progress = {});

}  // namespace objmap::pipeline
