#pragma once
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <future>
#include <mutex>
#include <thread>
#include <vector>

namespace objmap {

// Worker threads that live as long as a keyframe loop (objmap fuse's, objmap follow's) and run its
// jobs in the order given: the thread-local scratch of the PNG decoder, the box masks and the depth
// gate stays allocated from one keyframe to the next, where a thread per keyframe (std::async)
// starts cold and page-faults it in again every time.
template <typename Result>
class JobThreads {
 public:
  explicit JobThreads(std::size_t threads) {
    for (std::size_t t = 0; t < threads; ++t) threads_.emplace_back([this] { run(); });
  }
  ~JobThreads() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    cv_.notify_all();
    for (std::thread& t : threads_) t.join();
  }
  JobThreads(const JobThreads&) = delete;
  JobThreads& operator=(const JobThreads&) = delete;

  // Queues `job`; its result or exception comes through the future.
  std::future<Result> submit(std::function<Result()> job) {
    std::packaged_task<Result()> task(std::move(job));
    std::future<Result> result = task.get_future();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      queue_.push_back(std::move(task));
    }
    cv_.notify_one();
    return result;
  }

 private:
  void run() {
    for (;;) {
      std::packaged_task<Result()> task;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        cv_.wait(lock, [&] { return stop_ || !queue_.empty(); });
        if (queue_.empty()) return;  // stopped, every queued job run
        task = std::move(queue_.front());
        queue_.pop_front();
      }
      task();
    }
  }

  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::packaged_task<Result()>> queue_;
  bool stop_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace objmap
