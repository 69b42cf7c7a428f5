#pragma once
#include <condition_variable>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "objmap/segmentation/detect.h"
#include "objmap/segmentation/types.h"

// objmap follow --model: the detector on a thread of its own, on the newest keyframe only. A
// keyframe handed over while an earlier one still waits for the detector replaces it: the earlier
// one is skipped (fused without instances) and counted. Never more than one keyframe waits.
namespace objmap::pipeline {

class LatestDetector {
 public:
  // Loads the model (throws InputError as segmentation::Detector does).
  explicit LatestDetector(const segmentation::DetectOptions& options);
  ~LatestDetector();
  LatestDetector(const LatestDetector&) = delete;
  LatestDetector& operator=(const LatestDetector&) = delete;

  // Hands over the keyframe at `timestamp` with its colour image file; returns the timestamp of
  // the keyframe it replaced (skipped), if one waited.
  std::optional<double> submit(double timestamp, const std::filesystem::path& rgb_file);

  // The keyframe's instances once detected (then forgotten here); nullopt while it waits or runs.
  std::optional<segmentation::FrameSegmentation> take(double timestamp);

  // Blocks until nothing waits and nothing runs.
  void drain();

  // Images that could not be read (the keyframe then has no instances), one line each; taken.
  std::vector<std::string> take_warnings();

 private:
  void run();
  std::unique_ptr<segmentation::Detector> detector_;
  std::mutex mutex_;
  std::condition_variable wake_, idle_;
  std::optional<std::pair<double, std::filesystem::path>> waiting_;
  bool running_ = false, stop_ = false;
  std::map<double, segmentation::FrameSegmentation> done_;
  std::vector<std::string> warnings_;
  std::thread thread_;
};

}  // namespace objmap::pipeline
