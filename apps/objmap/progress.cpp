#include "progress.h"

#include <unistd.h>

#include <cstdio>

namespace objmap::app {

ProgressBar::ProgressBar(std::string label, std::size_t total, std::string unit)
    : label_(std::move(label)),
      total_(total),
      unit_(std::move(unit)),
      tty_(isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()) {}

ProgressBar::~ProgressBar() {
  if (!finished_ && tty_) std::fputc('\n', stderr);
}

void ProgressBar::update(std::size_t done) {
  if (finished_ || total_ == 0) return;
  const auto now = std::chrono::steady_clock::now();
  if (!have_first_) {
    have_first_ = true;
    first_done_ = done;
    first_time_ = now;
  }
  if (tty_) {
    if (now - last_draw_ < std::chrono::milliseconds(100) && done < total_) return;
    last_draw_ = now;
    draw(done, false);
  } else {
    const int decile = static_cast<int>(10 * done / total_);
    if (decile == last_decile_) return;
    last_decile_ = decile;
    draw(done, true);
  }
}

void ProgressBar::finish() {
  if (finished_) return;
  if (tty_ && total_ > 0) {
    draw(total_, false);
    std::fputc('\n', stderr);
  } else if (last_decile_ < 10 && total_ > 0) {
    draw(total_, true);
  }
  finished_ = true;
}

void ProgressBar::draw(std::size_t done, bool final_line) {
  const auto now = std::chrono::steady_clock::now();
  // From the first update when there has been progress since; else from the bar's start.
  const bool since_first = have_first_ && done > first_done_;
  const double seconds =
      std::chrono::duration<double>(now - (since_first ? first_time_ : start_)).count();
  const std::size_t counted = since_first ? done - first_done_ : done;
  const bool known = counted > 0 && seconds > 1e-3;
  const double rate = known ? counted / seconds : 0.0;
  const double eta = rate > 0 ? (total_ - done) / rate : 0.0;
  constexpr int kWidth = 24;
  const int filled = total_ ? static_cast<int>(kWidth * done / total_) : kWidth;
  std::string bar(filled, '#');
  bar.resize(kWidth, '.');
  char speed[64];
  if (known)
    std::snprintf(speed, sizeof speed, "%.1f %s/s  ETA %.0f s", rate, unit_.c_str(), eta);
  else
    std::snprintf(speed, sizeof speed, "-- %s/s", unit_.c_str());
  std::fprintf(stderr, "%s%-8s [%s] %zu/%zu  %s%s", final_line ? "" : "\r", label_.c_str(),
               bar.c_str(), done, total_, speed, final_line ? "\n" : "   ");
  std::fflush(stderr);
}

}  // namespace objmap::app
