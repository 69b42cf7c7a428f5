#pragma once
#include <cstddef>
#include <vector>

#include "objmap/geometry/voxel_key.h"

// A set of voxel keys: open addressing with linear probing, a key per 8-byte slot (stored XOR
// kNoVoxel, so that an empty slot is 0), at most 3/4 full. For keys met many times and wanted once
// each (a live dense map's touched voxels, fusion/voxel_map.h): its memory follows the distinct
// keys, not the times they were met.
namespace objmap::geometry {

class VoxelKeySet {
 public:
  std::size_t size() const { return size_; }
  std::size_t capacity() const { return slots_.size(); }

  // Adds `key` (not kNoVoxel); false when it was there.
  bool insert(VoxelKey key) {
    if ((size_ + 1) * 4 > slots_.size() * 3) grow();
    const VoxelKey stored = key ^ kNoVoxel;
    const std::size_t m = slots_.size() - 1;
    for (std::size_t i = index(key);; i = (i + 1) & m) {
      if (slots_[i] == stored) return false;
      if (slots_[i] == 0) {
        slots_[i] = stored;
        ++size_;
        return true;
      }
    }
  }

  // Hint: `key` will be inserted soon (hides the cache miss of a large set).
  void prefetch(VoxelKey key) const {
    if (!slots_.empty()) __builtin_prefetch(&slots_[index(key)], 1);
  }

  // f(key) for each key (in slot order), emptying the set as it goes. The slots are kept for the
  // next fill unless they are more than 8 times what these keys needed.
  template <typename F>
  void drain(F&& f) {
    for (VoxelKey& s : slots_)
      if (s != 0) {
        f(s ^ kNoVoxel);
        s = 0;
      }
    if (slots_.size() > 64 && slots_.size() > 8 * (size_ * 4 / 3 + 1))
      std::vector<VoxelKey>().swap(slots_);
    size_ = 0;
  }
  // drain() into `out` (appended).
  void take(std::vector<VoxelKey>& out) {
    out.reserve(out.size() + size_);
    drain([&out](VoxelKey key) { out.push_back(key); });
  }

 private:
  std::size_t index(VoxelKey key) const {
    return static_cast<std::size_t>(mix_voxel_key(key) >> shift_);
  }
  void grow() {
    std::vector<VoxelKey> old(slots_.empty() ? std::size_t{64} : slots_.size() * 2, 0);
    old.swap(slots_);
    int bits = 0;
    while ((std::size_t{1} << bits) < slots_.size()) ++bits;
    shift_ = 64 - bits;
    const std::size_t m = slots_.size() - 1;
    for (const VoxelKey s : old) {
      if (s == 0) continue;
      std::size_t i = index(s ^ kNoVoxel);
      while (slots_[i] != 0) i = (i + 1) & m;
      slots_[i] = s;
    }
  }

  std::vector<VoxelKey> slots_;
  std::size_t size_ = 0;
  int shift_ = 64;
};

}  // namespace objmap::geometry
