#pragma once
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <unordered_map>
#include <utility>

#include "objmap/core/types.h"
#include "objmap/geometry/bounds.h"

// The filtered part of records already made (ObjectMap::records), by object and content: objmap
// follow makes the record of every object at each publish, most of them unchanged since the last
// (an object out of view takes no observation). A record is reused only for the same object id,
// the same content (its voxels, their sums and support, its observation count: a 64-bit hash) and
// the same record options; anything else is made again. One entry per object (the latest).
namespace objmap::fusion {

// A cache's lookups that found an entry and that did not; its lock.
class CacheCounts {
 public:
  std::size_t hits() const;
  std::size_t misses() const;

 protected:
  mutable std::mutex mutex_;
  mutable std::size_t hits_ = 0, misses_ = 0;
};

class RecordCache : public CacheCounts {
 public:
  // What filter_record and the position and boxes make of an object's voxels.
  struct Filtered {
    std::uint64_t content = 0;
    PointCloud cloud;
    std::size_t points_voxel = 0, points_filtered = 0;
    double outlier_threshold = 0.0;
    Vec3 centroid = Vec3::Zero(), position = Vec3::Zero();
    Aabb aabb;
    Obb obb;
  };
  std::optional<Filtered> find(int id, std::uint64_t content) const;
  void put(int id, const Filtered& filtered);

 private:
  std::map<int, Filtered> by_id_;
};

// Values by the contents of two things (two 64-bit hashes), kept from one pass over them to the
// next: begin_pass() starts a pass, and the entries no pass used since the one before are dropped.
template <typename Value>
class PassCache : public CacheCounts {
 public:
  void begin_pass() {
    const std::lock_guard<std::mutex> lock(mutex_);
    before_ = std::move(now_);
    now_.clear();
  }
  std::optional<Value> find(std::uint64_t a, std::uint64_t b) {
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
  void put(std::uint64_t a, std::uint64_t b, const Value& value) {
    const std::lock_guard<std::mutex> lock(mutex_);
    now_[std::make_pair(a, b)] = value;
  }

 private:
  struct Hash {
    std::size_t operator()(const std::pair<std::uint64_t, std::uint64_t>& k) const {
      return static_cast<std::size_t>(k.first ^ (k.second * 0x9e3779b97f4a7c15ull));
    }
  };
  using Table = std::unordered_map<std::pair<std::uint64_t, std::uint64_t>, Value, Hash>;
  Table now_, before_;  // used in this pass; in the one before
};

// The merge pass's pair scores (ObjectMap::merge_pass, its pair rule) by the content of the two
// objects (a 64-bit hash of everything the score reads of each: voxels, their sums, the dilated
// support table, bounds, centroid, radius, class votes, observations' timestamps, classes and track
// ids).
struct PairVerdict {
  double p_id = 0.0, distance_m = 0.0, overlap = 0.0, score_p = 0.0;
  bool passes = false;  // no refusal
};
class PairCache : public PassCache<PairVerdict> {
 public:
  using Verdict = PairVerdict;
  // The class-confusion rule's supported share of one object on another (ObjectMap's
  // supported_share: the first's voxels against the second's support table), by the same hashes.
  PassCache<double> shares;
  void begin_pass() {
    PassCache<PairVerdict>::begin_pass();
    shares.begin_pass();
  }
};

// The duplicate check's surface contact of two clouds (fusion/duplicates.h) by their content (a
// 64-bit hash of each cloud's points; the query's with the touch distance folded in): objmap follow
// checks every pair at each publish, most of them unchanged since the last.
struct CloudContact {
  double distance_m = 0.0;  // shortest distance from the query cloud's points to the other's
  double share = 0.0;       // of the query cloud's points within the touch distance
};
class ContactCache : public PassCache<CloudContact> {
 public:
  using Contact = CloudContact;
};

}  // namespace objmap::fusion
