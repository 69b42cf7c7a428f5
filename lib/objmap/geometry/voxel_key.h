#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

#include "objmap/core/types.h"

// Voxel keys and a flat open-addressing hash table keyed by them. Shared by the dense voxel map and
// the per-object voxel sets (fusion/), so that every part of objmap agrees on which voxel a point
// falls in.
namespace objmap::geometry {

// A voxel is (ix, iy, iz) = floor(point / voxel_m), packed as 3 × 21 bits with an offset of 2^20:
// ±2^20 voxels per axis (±10 km at 1 cm). Sorting keys sorts by (ix, iy, iz). The all-ones value is
// never a valid key (bit 63 is always 0).
using VoxelKey = std::uint64_t;
constexpr VoxelKey kNoVoxel = ~VoxelKey{0};
constexpr std::int32_t kVoxelCoordLimit = 1 << 20;

inline VoxelKey pack_voxel(std::int32_t ix, std::int32_t iy, std::int32_t iz) {
  return (static_cast<VoxelKey>(ix + kVoxelCoordLimit) << 42) |
         (static_cast<VoxelKey>(iy + kVoxelCoordLimit) << 21) |
         static_cast<VoxelKey>(iz + kVoxelCoordLimit);
}

inline Eigen::Vector3i unpack_voxel(VoxelKey key) {
  constexpr VoxelKey mask = (VoxelKey{1} << 21) - 1;
  return {static_cast<int>((key >> 42) & mask) - kVoxelCoordLimit,
          static_cast<int>((key >> 21) & mask) - kVoxelCoordLimit,
          static_cast<int>(key & mask) - kVoxelCoordLimit};
}

// Grows the box [lo, hi] of voxel coordinates to hold `key`'s voxel; `any` is false before the
// first key (lo and hi are then set to it).
inline void extend_voxel_bounds(VoxelKey key, bool& any, Eigen::Vector3i& lo, Eigen::Vector3i& hi) {
  const Eigen::Vector3i ijk = unpack_voxel(key);
  if (!any) {
    lo = hi = ijk;
    any = true;
  } else {
    lo = lo.cwiseMin(ijk);
    hi = hi.cwiseMax(ijk);
  }
}

// floor() for |x| < 2^31 without a libm call (x86-64's baseline SSE2 has no rounding instruction).
inline std::int32_t fast_floor(float x) {
  const std::int32_t i = static_cast<std::int32_t>(x);  // truncates toward zero
  return i - static_cast<std::int32_t>(x < static_cast<float>(i));
}

// Voxel coordinates of `point` scaled by 1 / voxel size (`inv_voxel_m`) and the point's position
// inside its voxel in voxel units, each in [0, 1). False when the point is not finite or outside
// the key range.
inline bool voxel_coords(const Vec3f& point, float inv_voxel_m, Eigen::Vector3i& ijk,
                         Eigen::Vector3f& offset) {
  const float sx = point.x() * inv_voxel_m, sy = point.y() * inv_voxel_m,
              sz = point.z() * inv_voxel_m;
  constexpr float lim = static_cast<float>(kVoxelCoordLimit);
  // Written so that NaN fails the test.
  if (!(sx >= -lim && sx < lim && sy >= -lim && sy < lim && sz >= -lim && sz < lim)) return false;
  ijk = {fast_floor(sx), fast_floor(sy), fast_floor(sz)};
  offset = {sx - static_cast<float>(ijk.x()), sy - static_cast<float>(ijk.y()),
            sz - static_cast<float>(ijk.z())};
  return true;
}

// The key of the voxel holding `point` (metres) for 1 / voxel size `inv_voxel_m`, or kNoVoxel when
// the point is not finite or outside the key range.
inline VoxelKey voxel_key(const Vec3f& point, float inv_voxel_m) {
  const float sx = point.x() * inv_voxel_m, sy = point.y() * inv_voxel_m,
              sz = point.z() * inv_voxel_m;
  constexpr float lim = static_cast<float>(kVoxelCoordLimit);
  if (!(sx >= -lim && sx < lim && sy >= -lim && sy < lim && sz >= -lim && sz < lim))
    return kNoVoxel;
  return pack_voxel(fast_floor(sx), fast_floor(sy), fast_floor(sz));
}

// The key offsets of a voxel's 3×3×3 neighbourhood, itself included (offset 0, the 14th), in
// (dx, dy, dz) order: key + offset is the neighbour's key (for voxels not at the end of the key
// range).
inline const std::array<VoxelKey, 27>& neighbourhood_offsets() {
  static const std::array<VoxelKey, 27> offsets = [] {
    std::array<VoxelKey, 27> o{};
    int n = 0;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz)
          o[n++] = static_cast<VoxelKey>(static_cast<std::int64_t>(dx) * (std::int64_t{1} << 42) +
                                         static_cast<std::int64_t>(dy) * (std::int64_t{1} << 21) +
                                         static_cast<std::int64_t>(dz));
    return o;
  }();
  return offsets;
}

// MurmurHash3 finaliser: every key bit reaches the high bits used for the slot index and the low
// bits used to pick a shard.
inline std::uint64_t mix_voxel_key(VoxelKey key) {
  key ^= key >> 33;
  key *= 0xff51afd7ed558ccdULL;
  key ^= key >> 33;
  key *= 0xc4ceb9fe1a85ec53ULL;
  key ^= key >> 33;
  return key;
}

// Zeroed memory mapped from the kernel, transparent huge pages asked for (nullptr on failure), and
// its release (voxel_key.cpp).
void* map_zeroed(std::size_t bytes);
void unmap(void* p, std::size_t bytes);

// Open addressing with linear probing, power-of-two capacity, at most 5/8 full. Keys and values sit
// in one slot array (one cache line for a probe and the update). Entries leave only in bulk
// (erase, the dense map's pruning). Iteration order depends on the insertion history; callers
// that export sort by key.
//
// A slot stores its key XOR kNoVoxel, so that an empty slot (key kNoVoxel, value Value{}) is all
// zero bits: the slot array is a zeroed allocation (every page written once when it is made, see
// allocate), not filled again when entries land or the table grows. Value must be trivially
// copyable and Value{} all zero bits (integers, floats, structs of them).
template <typename Value>
class VoxelHashTable {
  static_assert(std::is_trivially_copyable<Value>::value,
                "VoxelHashTable stores its slots in zeroed raw memory");

 public:
  struct Slot {
    VoxelKey stored;  // key ^ kNoVoxel: 0 for an empty slot
    Value value;
    VoxelKey key() const { return stored ^ kNoVoxel; }
    bool empty() const { return stored == 0; }
  };

  VoxelHashTable() = default;
  explicit VoxelHashTable(std::size_t expected) { reserve(expected); }
  VoxelHashTable(const VoxelHashTable& other) { *this = other; }
  VoxelHashTable(VoxelHashTable&& other) noexcept { *this = std::move(other); }
  VoxelHashTable& operator=(const VoxelHashTable& other) {
    if (this == &other) return *this;
    Slots copy;
    if (other.capacity_ > 0) {
      copy = allocate(other.capacity_, /*zeroed=*/false);
      std::memcpy(static_cast<void*>(copy.get()), other.slots_.get(),
                  other.capacity_ * sizeof(Slot));
    }
    slots_ = std::move(copy);
    capacity_ = other.capacity_;
    size_ = other.size_;
    shift_ = other.shift_;
    return *this;
  }
  VoxelHashTable& operator=(VoxelHashTable&& other) noexcept {
    slots_ = std::move(other.slots_);
    capacity_ = std::exchange(other.capacity_, 0);
    size_ = std::exchange(other.size_, 0);
    shift_ = std::exchange(other.shift_, 64);
    return *this;
  }

  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  std::size_t capacity() const { return capacity_; }
  std::size_t memory_bytes() const { return capacity_ * sizeof(Slot); }

  void reserve(std::size_t expected) {
    std::size_t cap = 16;
    while (cap * 5 < expected * 8) cap *= 2;
    if (cap > capacity_) rehash(cap);
  }

  // Empties the table and keeps its slots (no allocation when refilled to the same size). An empty
  // table's slots are all zero already (entries are never erased one by one): nothing to write.
  void reset() {
    if (size_ == 0) return;
    std::memset(static_cast<void*>(slots_.get()), 0, capacity_ * sizeof(Slot));
    size_ = 0;
  }

  void clear() {
    slots_.reset();
    capacity_ = 0;
    size_ = 0;
    shift_ = 64;
  }

  // The value of `key`, inserted value-initialised when absent (key must not be kNoVoxel).
  Value& operator[](VoxelKey key) {
    if ((size_ + 1) * 8 > capacity_ * 5) rehash(capacity_ == 0 ? 16 : capacity_ * 2);
    const VoxelKey stored = key ^ kNoVoxel;
    std::size_t i = index(key);
    const std::size_t m = capacity_ - 1;
    Slot* const slots = slots_.get();
    while (true) {
      Slot& s = slots[i];
      if (s.stored == stored) return s.value;
      if (s.stored == 0) {
        s.stored = stored;
        ++size_;
        return s.value;
      }
      i = (i + 1) & m;
    }
  }

  const Value* find(VoxelKey key) const {
    if (capacity_ == 0) return nullptr;
    const VoxelKey stored = key ^ kNoVoxel;
    std::size_t i = index(key);
    const std::size_t m = capacity_ - 1;
    const Slot* const slots = slots_.get();
    while (true) {
      const Slot& s = slots[i];
      if (s.stored == stored) return &s.value;
      if (s.stored == 0) return nullptr;
      i = (i + 1) & m;
    }
  }
  Value* find(VoxelKey key) {
    return const_cast<Value*>(static_cast<const VoxelHashTable*>(this)->find(key));
  }
  bool contains(VoxelKey key) const { return find(key) != nullptr; }

  // Hint: `key`'s home slot will be needed soon (hides the cache miss of a large table).
  void prefetch(VoxelKey key) const {
    if (capacity_ > 0) __builtin_prefetch(&slots_[index(key)], 1);
  }

  // f(key, value) for every entry, in slot order.
  template <typename F>
  void for_each(F&& f) const {
    const Slot* const slots = slots_.get();
    for (std::size_t i = 0; i < capacity_; ++i)
      if (!slots[i].empty()) f(slots[i].key(), slots[i].value);
  }

  // Removes `key`'s entry (false: there was none). The capacity stays; no tombstone is left
  // (backward-shift deletion), so lookups do not probe through erased slots. O(its cluster).
  bool erase(VoxelKey key);

  // All keys, ascending.
  std::vector<VoxelKey> sorted_keys() const;

 private:
  // Zeroed slot arrays of 2 MB and more are mapped from the kernel (zeroed pages) with transparent
  // huge pages asked for: a large table is touched all over, and one fault per 2 MB instead of per
  // 4 KB is most of what filling it costs. Smaller ones, and a copy's slots whatever their size
  // (every byte written by the copy: memory the allocator kept, core/memory.h, is reused without
  // the kernel zeroing and faulting in pages overwritten at once), come from malloc.
  static constexpr std::size_t kMapBytes = std::size_t{2} << 20;
  struct Free {
    std::size_t bytes = 0;
    bool mapped = false;  // by map_zeroed, not malloc
    void operator()(Slot* p) const { free_slots(p, bytes, mapped); }
  };
  using Slots = std::unique_ptr<Slot[], Free>;
  static Slots allocate(std::size_t cap, bool zeroed) {
    const std::size_t bytes = cap * sizeof(Slot);
    const bool mapped = zeroed && bytes >= kMapBytes;
    void* p = mapped ? map_zeroed(bytes) : std::malloc(bytes);
    if (!p) throw std::bad_alloc();
    // Zeroed by writing, not by calloc: calloc leaves fresh pages to the kernel, and a probe's read
    // of such a page maps the shared zero page, whose replacement at the write that follows is a
    // second fault and a TLB flush on the other threads' cores (as map_zeroed's pages, written).
    // explicit_bzero: the compiler would turn malloc + memset back into calloc.
    if (zeroed && !mapped) explicit_bzero(p, bytes);
    return Slots(static_cast<Slot*>(p), Free{bytes, mapped});
  }
  static void free_slots(Slot* p, std::size_t bytes, bool mapped) {
    if (mapped)
      unmap(p, bytes);
    else
      std::free(p);
  }
  std::size_t index(VoxelKey key) const {
    return static_cast<std::size_t>(mix_voxel_key(key) >> shift_);
  }
  void rehash(std::size_t cap) {
    Slots old = allocate(cap, /*zeroed=*/true);
    old.swap(slots_);
    const std::size_t old_capacity = std::exchange(capacity_, cap);
    int bits = 0;
    while ((std::size_t{1} << bits) < cap) ++bits;
    shift_ = 64 - bits;
    const std::size_t m = cap - 1;
    Slot* const slots = slots_.get();
    for (std::size_t k = 0; k < old_capacity; ++k) {
      const Slot& s = old[k];
      if (s.empty()) continue;
      std::size_t i = index(s.key());
      while (!slots[i].empty()) i = (i + 1) & m;
      slots[i] = s;
    }
  }

  Slots slots_;
  std::size_t capacity_ = 0;
  std::size_t size_ = 0;
  int shift_ = 64;
};

}  // namespace objmap::geometry

#include <algorithm>

template <typename Value>
bool objmap::geometry::VoxelHashTable<Value>::erase(VoxelKey key) {
  if (capacity_ == 0) return false;
  const std::size_t m = capacity_ - 1;
  const VoxelKey stored = key ^ kNoVoxel;
  std::size_t hole = index(key);
  while (slots_[hole].stored != stored) {
    if (slots_[hole].empty()) return false;
    hole = (hole + 1) & m;
  }
  // Backward-shift deletion (Knuth's Algorithm R): the hole takes the next entry of its cluster
  // whose home is not in (hole, j], and so on until the cluster ends.
  for (std::size_t j = hole;;) {
    std::memset(static_cast<void*>(&slots_[hole]), 0, sizeof(Slot));
    while (true) {
      j = (j + 1) & m;
      if (slots_[j].empty()) {
        --size_;
        return true;
      }
      const std::size_t home = index(slots_[j].key());
      const bool stays = hole <= j ? (hole < home && home <= j) : (hole < home || home <= j);
      if (!stays) break;
    }
    slots_[hole] = slots_[j];
    hole = j;
  }
}

template <typename Value>
std::vector<objmap::geometry::VoxelKey> objmap::geometry::VoxelHashTable<Value>::sorted_keys()
    const {
  std::vector<VoxelKey> keys;
  keys.reserve(size_);
  for_each([&](VoxelKey key, const Value&) { keys.push_back(key); });
  std::sort(keys.begin(), keys.end());
  return keys;
}
