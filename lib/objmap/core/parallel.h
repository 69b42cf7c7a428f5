#pragma once
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

// A small work-sharing loop for the stages that split independent items over threads (the scene
// generator, the re-made observations and ICP of objmap correct).

namespace objmap {

// Number of worker threads for `requested` (0 = all hardware threads), at least 1.
inline int resolve_threads(int requested) {
  if (requested > 0) return requested;
  const unsigned hw = std::thread::hardware_concurrency();
  return hw == 0 ? 1 : static_cast<int>(hw);
}

// Calls fn(i) for i in [0, n) on `threads` threads (items handed out one at a time). The results
// must not depend on which thread runs an item: each item writes only its own output. The first
// exception thrown by an item is rethrown here.
template <typename Fn>
void parallel_for(std::size_t n, int threads, Fn&& fn) {
  const int workers = std::max(1, std::min<int>(resolve_threads(threads), static_cast<int>(n)));
  if (workers <= 1) {
    for (std::size_t i = 0; i < n; ++i) fn(i);
    return;
  }
  std::atomic<std::size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&] {
    for (;;) {
      const std::size_t i = next.fetch_add(1);
      if (i >= n) return;
      try {
        fn(i);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
        next = n;
        return;
      }
    }
  };
  std::vector<std::thread> pool;
  for (int w = 1; w < workers; ++w) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace objmap
