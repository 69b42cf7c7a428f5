#include "objmap/fusion/record_cache.h"

namespace objmap::fusion {

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

void RecordCache::put(int id, Filtered filtered) {
  const std::lock_guard<std::mutex> lock(mutex_);
  by_id_[id] = std::move(filtered);
}

std::size_t RecordCache::hits() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return hits_;
}

std::size_t RecordCache::misses() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return misses_;
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

std::size_t PairCache::hits() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return hits_;
}

std::size_t PairCache::misses() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return misses_;
}

}  // namespace objmap::fusion
