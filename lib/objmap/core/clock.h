#pragma once
#include <chrono>

// The wall clock of the stages' timings (run.json "performance", correction.json "seconds") and the
// process's peak memory.
namespace objmap {

using Clock = std::chrono::steady_clock;

// Seconds from `t0` to now.
inline double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The process's peak resident memory so far, kB (getrusage).
long peak_rss_kb();

}  // namespace objmap
