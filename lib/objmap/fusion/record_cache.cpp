#include "objmap/fusion/record_cache.h"

namespace objmap::fusion {

std::size_t CacheCounts::hits() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return hits_;
}

std::size_t CacheCounts::misses() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return misses_;
}

std::optional<RecordCache::Filtered> RecordCache::find(int id, std::uint64_t content) const {
  const std::lock_guard<std::mutex> lock(mutex_);
  const auto it = by_id_.find(id);
  if (it == by_id_.end() || it->second.content != content) {
    ++misses_;
    return std::nullopt;
  }
  ++hits_;
  return it->second;
}

void RecordCache::put(int id, const Filtered& filtered) {
  const std::lock_guard<std::mutex> lock(mutex_);
  by_id_[id] = filtered;
}

void PairCache::begin_pass() {
  const std::lock_guard<std::mutex> lock(mutex_);
  before_ = std::move(now_);
  now_.clear();
}

std::optional<PairCache::Verdict> PairCache::find(std::uint64_t a, std::uint64_t b) {
  const std::lock_guard<std::mutex> lock(mutex_);
  const auto key = std::make_pair(a, b);
  if (const auto it = now_.find(key); it != now_.end()) {
    ++hits_;
    return it->second;
  }
  if (const auto it = before_.find(key); it != before_.end()) {
    ++hits_;
    now_.emplace(key, it->second);
    return it->second;
  }
  ++misses_;
  return std::nullopt;
}

void PairCache::put(std::uint64_t a, std::uint64_t b, const Verdict& verdict) {
  const std::lock_guard<std::mutex> lock(mutex_);
  now_[std::make_pair(a, b)] = verdict;
}

}  // namespace objmap::fusion
