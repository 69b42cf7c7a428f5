#include "objmap/pipeline/follow_detect.h"

#include <chrono>
#include <utility>

#include "objmap/core/error.h"
#include "objmap/io/image.h"

namespace objmap::pipeline {

LatestDetector::LatestDetector(const segmentation::DetectOptions& options)
    : detector_(std::make_unique<segmentation::Detector>(options)), thread_([this] { run(); }) {}

LatestDetector::~LatestDetector() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

std::optional<double> LatestDetector::submit(double timestamp,
                                             const std::filesystem::path& rgb_file) {
  std::optional<double> skipped;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (waiting_) skipped = waiting_->first;
    waiting_.emplace(timestamp, rgb_file);
  }
  wake_.notify_all();
  return skipped;
}

std::optional<segmentation::FrameSegmentation> LatestDetector::take(double timestamp) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = done_.find(timestamp);
  if (it == done_.end()) return std::nullopt;
  segmentation::FrameSegmentation frame = std::move(it->second);
  done_.erase(it);
  return frame;
}

void LatestDetector::drain() {
  std::unique_lock<std::mutex> lock(mutex_);
  idle_.wait(lock, [this] { return !waiting_ && !running_; });
}

std::vector<std::string> LatestDetector::take_warnings() {
  std::lock_guard<std::mutex> lock(mutex_);
  return std::exchange(warnings_, {});
}

void LatestDetector::run() {
  for (;;) {
    std::pair<double, std::filesystem::path> job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return stop_ || waiting_; });
      if (stop_) return;
      job = std::move(*waiting_);
      waiting_.reset();
      running_ = true;
    }
    segmentation::FrameSegmentation frame;
    frame.timestamp = job.first;
    frame.source = job.second.string();
    std::string warning;
    // The image was renamed into place before it was listed; a read that fails is tried again
    // a little later, then the keyframe goes without instances.
    for (int attempt = 0; attempt < 3; ++attempt) {
      try {
        frame.instances = detector_->detect(io::read_rgb(job.second, 0, 0), job.second.string());
        warning.clear();
        break;
      } catch (const InputError& e) {
        warning = std::string(e.what()) + "; detected on no instance";
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      }
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_[job.first] = std::move(frame);
      if (!warning.empty()) warnings_.push_back(warning);
      running_ = false;
    }
    idle_.notify_all();
  }
}

}  // namespace objmap::pipeline
