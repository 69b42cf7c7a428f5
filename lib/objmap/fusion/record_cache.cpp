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

}  // namespace objmap::fusion
