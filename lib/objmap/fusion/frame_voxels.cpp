#include "objmap/fusion/frame_voxels.h"

#include <algorithm>
#include <cstring>

#include "objmap/geometry/voxel_key_sse.h"

namespace objmap::fusion {

using geometry::kNoVoxel;

namespace {

// One row's scratch, as plain arrays (FrameVoxels' buffers): each column's voxel (kNoVoxel: none)
// and offsets inside it; the row's runs (first columns); prefix sums of the offsets and colours.
struct RowArrays {
  VoxelKey* key;
  float *off_x, *off_y, *off_z;
  std::uint32_t* starts;
  double *prefix_x, *prefix_y, *prefix_z;
  std::uint32_t *prefix_r, *prefix_g, *prefix_b;
};

// A row's pixels: looked at (in the mask), with a valid depth, and of those dropped (not finite
// or out of the key range).
struct RowCounts {
  std::uint32_t considered = 0, points = 0, dropped = 0;
};

// The columns of a row: `cols` of them from roi_x, one every `stride` pixels.
struct RowColumns {
  int roi_x, stride, cols;
};

#if defined(__SSE2__)
// Step 1 with stride 1, four columns at a time: the scalar loop's float operations in the same
// order (the same bits), without a branch per pixel (an invalid pixel's values are computed from 0
// and discarded). Keys are packed in two 64-bit lanes per half. Returns the first column left to
// the scalar loop.
inline int row_keys_sse(const geometry::FrameRow row, const geometry::PixelTransform& T,
                        float inv_voxel, const RowColumns rc, const RowArrays a, RowCounts& n) {
  std::uint32_t row_considered = 0, row_points = 0, row_dropped = 0;
  const __m128 inv_f = _mm_set1_ps(T.inv_factor), inv_v = _mm_set1_ps(inv_voxel);
  const __m128i raw_lo = _mm_set1_epi32(static_cast<int>(T.raw_min) - 1);
  const __m128i raw_hi = _mm_set1_epi32(static_cast<int>(T.raw_max) + 1);
  const __m128i bias = _mm_set1_epi32(geometry::kVoxelCoordLimit);
  const __m128i zero = _mm_setzero_si128(), ones = _mm_set1_epi32(-1);
  __m128 Rm[9], Tv[3];
  for (int k = 0; k < 9; ++k) Rm[k] = _mm_set1_ps(T.r[k]);
  for (int k = 0; k < 3; ++k) Tv[k] = _mm_set1_ps(T.t[k]);
  int c = 0;
  for (; c + 4 <= rc.cols; c += 4) {
    const int u = rc.roi_x + c;
    std::uint64_t raw4;
    std::memcpy(&raw4, row.depth + u, 8);
    const __m128i raw = _mm_unpacklo_epi16(_mm_cvtsi64_si128(static_cast<long long>(raw4)), zero);
    __m128i looked = ones;
    if (row.mask) {
      std::uint32_t m4;
      std::memcpy(&m4, row.mask + u, 4);
      const __m128i m = _mm_unpacklo_epi16(
          _mm_unpacklo_epi8(_mm_cvtsi32_si128(static_cast<int>(m4)), zero), zero);
      looked = _mm_xor_si128(_mm_cmpeq_epi32(m, zero), ones);
    }
    const __m128i depth_ok = _mm_and_si128(
        looked, _mm_and_si128(_mm_cmpgt_epi32(raw, raw_lo), _mm_cmplt_epi32(raw, raw_hi)));
    const __m128 z = _mm_mul_ps(_mm_cvtepi32_ps(raw), inv_f);
    const __m128 x = _mm_mul_ps(_mm_loadu_ps(row.x_over_z + u), z);
    const __m128 y = _mm_mul_ps(_mm_loadu_ps(row.y_over_z + u), z);
    const auto scaled = [&](int i) {  // (R · p + t)[i] / voxel size, as PixelTransform
      const __m128 w = _mm_add_ps(_mm_mul_ps(Rm[3 * i], x), _mm_mul_ps(Rm[3 * i + 1], y));
      return _mm_mul_ps(_mm_add_ps(_mm_add_ps(w, _mm_mul_ps(Rm[3 * i + 2], z)), Tv[i]), inv_v);
    };
    const geometry::VoxelCoords4 v4 = geometry::voxel_coords4(scaled(0), scaled(1), scaled(2));
    const __m128i ix = _mm_add_epi32(v4.ix, bias), iy = _mm_add_epi32(v4.iy, bias),
                  iz = _mm_add_epi32(v4.iz, bias);
    const __m128i valid = _mm_and_si128(depth_ok, _mm_castps_si128(v4.ok));
    const __m128 valid_ps = _mm_castsi128_ps(valid);  // offsets of invalid pixels: 0
    _mm_storeu_ps(a.off_x + c, _mm_and_ps(v4.fx, valid_ps));
    _mm_storeu_ps(a.off_y + c, _mm_and_ps(v4.fy, valid_ps));
    _mm_storeu_ps(a.off_z + c, _mm_and_ps(v4.fz, valid_ps));
    const auto keys = [&](__m128i ka, __m128i kb, __m128i kc, __m128i v) {  // 2 lanes
      const __m128i k =
          _mm_or_si128(_mm_or_si128(_mm_slli_epi64(ka, 42), _mm_slli_epi64(kb, 21)), kc);
      return _mm_or_si128(k, _mm_xor_si128(v, ones));  // invalid: all ones (kNoVoxel)
    };
    _mm_storeu_si128(reinterpret_cast<__m128i*>(a.key + c),
                     keys(_mm_unpacklo_epi32(ix, zero), _mm_unpacklo_epi32(iy, zero),
                          _mm_unpacklo_epi32(iz, zero), _mm_unpacklo_epi32(valid, valid)));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(a.key + c + 2),
                     keys(_mm_unpackhi_epi32(ix, zero), _mm_unpackhi_epi32(iy, zero),
                          _mm_unpackhi_epi32(iz, zero), _mm_unpackhi_epi32(valid, valid)));
    const int looked_bits = _mm_movemask_ps(_mm_castsi128_ps(looked));
    const int depth_bits = _mm_movemask_ps(_mm_castsi128_ps(depth_ok));
    const int valid_bits = _mm_movemask_ps(_mm_castsi128_ps(valid));
    // Set bits of a 4-bit mask (x86-64's baseline has no popcnt instruction).
    static constexpr std::uint8_t kBits[16] = {0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4};
    row_considered += kBits[looked_bits];
    row_points += kBits[depth_bits];
    row_dropped += kBits[depth_bits & ~valid_bits];
  }
  n.considered += row_considered;
  n.points += row_points;
  n.dropped += row_dropped;
  return c;
}
#endif

// Step 1: each column's voxel and offsets (an invalid pixel's key is kNoVoxel), as
// geometry::backproject: the depth range on raw values, eqs 11-15 in float; as VoxelMap::insert:
// the voxel and the offset inside it, in voxel units.
inline RowCounts row_keys(const geometry::FrameRow& row, const geometry::PixelTransform& T,
                          float inv_voxel, const RowColumns& rc, const RowArrays& a) {
  RowCounts n;
  int c = 0;  // first column left to the scalar loop
#if defined(__SSE2__)
  if (rc.stride == 1) c = row_keys_sse(row, T, inv_voxel, rc, a, n);
#endif
  const std::uint16_t* drow = row.depth;
  const std::uint8_t* mrow = row.mask;
  const float* rx = row.x_over_z;
  const float* ry = row.y_over_z;
  VoxelKey* const key_now = a.key;
  float* const off_x = a.off_x;
  float* const off_y = a.off_y;
  float* const off_z = a.off_z;
  const int cols = rc.cols, roi_x = rc.roi_x, s = rc.stride;
  const std::uint32_t raw_min = T.raw_min, raw_max = T.raw_max;
  const float inv_factor = T.inv_factor;
  std::uint32_t row_considered = 0, row_points = 0, row_dropped = 0;
  for (; c < cols; ++c) {
    const int u = roi_x + c * s;
    key_now[c] = kNoVoxel;
    off_x[c] = off_y[c] = off_z[c] = 0.f;
    if (mrow && !mrow[u]) continue;
    ++row_considered;
    const std::uint32_t raw = drow[u];
    if (raw < raw_min || raw > raw_max) continue;
    ++row_points;
    const float z = static_cast<float>(raw) * inv_factor;
    const float x = rx[u] * z;
    const float y = ry[u] * z;
    const Vec3f p(T.world_x(x, y, z), T.world_y(x, y, z), T.world_z(x, y, z));
    Eigen::Vector3i ijk;
    Eigen::Vector3f offset;
    if (!geometry::voxel_coords(p, inv_voxel, ijk, offset)) {
      ++row_dropped;
      continue;
    }
    key_now[c] = geometry::pack_voxel(ijk.x(), ijk.y(), ijk.z());
    off_x[c] = offset.x();
    off_y[c] = offset.y();
    off_z[c] = offset.z();
  }
  n.considered += row_considered;
  n.points += row_points;
  n.dropped += row_dropped;
  return n;
}

// Step 2: the row's runs: the columns where the key changes, found without a branch per pixel, and
// prefix sums of the offsets (in double: a difference is exact to ~1e-13) and colours (crow:
// nullptr without), so that a run's sums are subtractions. Returns the number of runs.
inline int row_runs(const cv::Vec3b* crow, const RowColumns& rc, const RowArrays& a) {
  const int cols = rc.cols, roi_x = rc.roi_x, s = rc.stride;
  const bool colour = crow != nullptr;
  const VoxelKey* const key_now = a.key;
  const float *const off_x = a.off_x, *const off_y = a.off_y, *const off_z = a.off_z;
  std::uint32_t* const starts = a.starts;
  double *const prefix_x = a.prefix_x, *const prefix_y = a.prefix_y, *const prefix_z = a.prefix_z;
  std::uint32_t *const prefix_r = a.prefix_r, *const prefix_g = a.prefix_g,
                       *const prefix_b = a.prefix_b;
  int runs = 0;
  VoxelKey prev = cols > 0 ? key_now[0] ^ 1 : 0;  // column 0 starts a run
  double ax = 0, ay = 0, az = 0;
  std::uint32_t ar = 0, ag = 0, ab = 0;
  for (int c = 0; c < cols; ++c) {
    const VoxelKey key = key_now[c];
    starts[runs] = c;
    runs += key != prev;
    prev = key;
    prefix_x[c] = ax;
    prefix_y[c] = ay;
    prefix_z[c] = az;
    ax += off_x[c];
    ay += off_y[c];
    az += off_z[c];
    if (colour) {
      prefix_r[c] = ar;
      prefix_g[c] = ag;
      prefix_b[c] = ab;
      const cv::Vec3b& bgr = crow[roi_x + c * s];
      ar += bgr[2];
      ag += bgr[1];
      ab += bgr[0];
    }
  }
  starts[runs] = cols;
  prefix_x[cols] = ax;
  prefix_y[cols] = ay;
  prefix_z[cols] = az;
  prefix_r[cols] = ar;
  prefix_g[cols] = ag;
  prefix_b[cols] = ab;
  return runs;
}

// Step 3: each run of a voxel added to the voxel's sum, entry_of(key) (the entry the cache holds
// for the voxel, or a new one).
template <typename EntryOf>
inline void add_runs(const RowArrays& a, int runs, bool colour, const EntryOf& entry_of) {
  const VoxelKey* const key_now = a.key;
  const std::uint32_t* const starts = a.starts;
  const double *const prefix_x = a.prefix_x, *const prefix_y = a.prefix_y,
                      *const prefix_z = a.prefix_z;
  const std::uint32_t *const prefix_r = a.prefix_r, *const prefix_g = a.prefix_g,
                             *const prefix_b = a.prefix_b;
  for (int r = 0; r < runs; ++r) {
    const int first = starts[r], end = starts[r + 1];
    const VoxelKey key = key_now[first];
    if (key == kNoVoxel) continue;
    VoxelData& sum = entry_of(key);
    sum.offset_sum[0] += static_cast<float>(prefix_x[end] - prefix_x[first]);
    sum.offset_sum[1] += static_cast<float>(prefix_y[end] - prefix_y[first]);
    sum.offset_sum[2] += static_cast<float>(prefix_z[end] - prefix_z[first]);
    const auto run_points = static_cast<std::uint32_t>(end - first);
    sum.count += run_points;
    if (colour) {
      sum.color_sum[0] += prefix_r[end] - prefix_r[first];
      sum.color_sum[1] += prefix_g[end] - prefix_g[first];
      sum.color_sum[2] += prefix_b[end] - prefix_b[first];
      sum.color_count += run_points;
    }
  }
}

}  // namespace

void frame_voxels(const geometry::RayTable& rays, const geometry::DepthFrame& frame,
                  const geometry::BackprojectOptions& options, const VoxelMap& map,
                  FrameVoxels& out) {
  options.check();
  geometry::check_depth_frame(rays, frame);
  cv::Rect roi(0, 0, rays.width, rays.height);
  if (!frame.roi.empty()) roi &= frame.roi;
  const int s = options.stride;
  const int cols = roi.empty() ? 0 : (roi.width + s - 1) / s;
  const RowColumns rc{roi.x, s, cols};

  // 0. The output emptied and the row scratch sized (kept from frame to frame: no allocation once
  //    warm).
  const std::size_t shards = map.shard_count();
  out.shards_.resize(shards);
  for (auto& entries : out.shards_) entries.clear();
  out.points_ = out.dropped_ = 0;
  out.considered_ = 0;
  out.voxel_m_ = map.voxel_m();
  out.cache_.assign(FrameVoxels::kCacheSlots, FrameVoxels::CacheSlot{});
  out.row_key_.resize(static_cast<std::size_t>(cols));
  out.row_offset_.resize(3 * static_cast<std::size_t>(cols));
  const std::size_t cols1 = static_cast<std::size_t>(cols) + 1;
  out.row_start_.resize(cols1);
  out.row_prefix_.resize(3 * cols1);
  out.row_color_prefix_.resize(3 * cols1);
  float* const off = out.row_offset_.data();
  double* const prefix = out.row_prefix_.data();
  std::uint32_t* const color_prefix = out.row_color_prefix_.data();
  const RowArrays arrays{out.row_key_.data(),
                         off,
                         off + cols,
                         off + 2 * cols,
                         out.row_start_.data(),
                         prefix,
                         prefix + cols1,
                         prefix + 2 * cols1,
                         color_prefix,
                         color_prefix + cols1,
                         color_prefix + 2 * cols1};

  // As geometry::backproject: the depth range on raw values, eqs 11-15 in float.
  const geometry::PixelTransform T(rays, frame, options);
  // As VoxelMap::insert: the voxel and the offset inside it, in voxel units.
  const float inv_voxel = static_cast<float>(1.0 / map.voxel_m());
  const bool colour = frame.bgr != nullptr;
  // A voxel's entry: the one the cache holds for it, or a new one (the cache slot then points to
  // it).
  FrameVoxels::CacheSlot* const cache = out.cache_.data();
  const auto entry_of = [&](VoxelKey key) -> VoxelData& {
    FrameVoxels::CacheSlot& slot = cache[FrameVoxels::cache_slot(key)];
    if (slot.key == key) return out.shards_[slot.shard][slot.index].sum;
    const std::size_t sh = map.shard_of(key);
    std::vector<FrameVoxels::Entry>& entries = out.shards_[sh];
    slot.key = key;
    slot.shard = static_cast<std::uint32_t>(sh);
    slot.index = static_cast<std::uint32_t>(entries.size());
    FrameVoxels::Entry& e = entries.emplace_back();
    e.key = key;
    return e.sum;
  };

  std::uint64_t points = 0, dropped = 0;
  std::size_t considered = 0;
  for (int v = roi.y; v < roi.y + roi.height; v += s) {
    const geometry::FrameRow row(rays, frame, v);
    // 1. Each column's voxel and offsets (an invalid pixel's key is kNoVoxel).
    const RowCounts n = row_keys(row, T, inv_voxel, rc, arrays);
    considered += n.considered;
    points += n.points;
    dropped += n.dropped;
    // 2. The row's runs of one voxel and the prefix sums of their offsets and colours.
    const int runs = row_runs(colour ? row.bgr : nullptr, rc, arrays);
    // 3. Each run added to its voxel's entry.
    add_runs(arrays, runs, colour, entry_of);
  }
  out.points_ = points;
  out.dropped_ = dropped;
  out.considered_ = considered;
}

std::size_t FrameVoxels::entries() const {
  std::size_t n = 0;
  for (const auto& e : shards_) n += e.size();
  return n;
}

}  // namespace objmap::fusion
