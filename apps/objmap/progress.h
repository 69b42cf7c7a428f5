#pragma once
#include <chrono>
#include <cstddef>
#include <string>

namespace objmap::app {

// A progress bar on stderr: "fuse  [#######.....]  57/174  41.2 frames/s  ETA 3 s". On a terminal
// it redraws one line; otherwise (CI, a log file) it prints a line at every 10% so logs stay short.
class ProgressBar {
 public:
  ProgressBar(std::string label, std::size_t total, std::string unit = "frames");
  void update(std::size_t done);
  void finish();
  ~ProgressBar();

 private:
  std::string label_;
  std::size_t total_;
  std::string unit_;
  bool tty_;
  bool finished_ = false;
  int last_decile_ = -1;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_{};
  // The rate is measured from the first update on (a bar made when the first item is done would
  // otherwise divide by almost no time): none is shown before a second update.
  std::size_t first_done_ = 0;
  std::chrono::steady_clock::time_point first_time_{};
  bool have_first_ = false;
  void draw(std::size_t done, bool final_line);
};

}  // namespace objmap::app
