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

}  // namespace objmap::fusion
