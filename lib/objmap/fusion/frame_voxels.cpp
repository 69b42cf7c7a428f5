#include "objmap/fusion/frame_voxels.h"

#include <algorithm>
#include <cstring>

#include "objmap/geometry/voxel_key_sse.h"

namespace objmap::fusion {

using geometry::kNoVoxel;

void frame_voxels(const geometry::RayTable& rays, const geometry::DepthFrame& frame,
                  const geometry::BackprojectOptions& options, const VoxelMap& map,
                  FrameVoxels& out) {
  options.check();
  geometry::check_depth_frame(rays, frame);
  cv::Rect roi(0, 0, rays.width, rays.height);
  if (!frame.roi.empty()) roi &= frame.roi;
  const int s = options.stride;
  const int cols = roi.empty() ? 0 : (roi.width + s - 1) / s;

  const std::size_t shards = map.shard_count();
  out.shards_.resize(shards);
  for (auto& entries : out.shards_) entries.clear();
  out.points_ = out.dropped_ = 0;
  out.considered_ = 0;
  out.voxel_m_ = map.voxel_m();
  out.cache_.assign(FrameVoxels::kCacheSlots, FrameVoxels::CacheSlot{});
  out.row_key_.resize(static_cast<std::size_t>(cols));
  out.row_offset_.resize(3 * static_cast<std::size_t>(cols));
  VoxelKey* const key_now = out.row_key_.data();
  float* const off_x = out.row_offset_.data();
  float* const off_y = off_x + cols;
  float* const off_z = off_y + cols;
  const std::size_t cols1 = static_cast<std::size_t>(cols) + 1;
  out.row_start_.resize(cols1);
  out.row_prefix_.resize(3 * cols1);
  out.row_color_prefix_.resize(3 * cols1);
  std::uint32_t* const starts = out.row_start_.data();
  double* const prefix_x = out.row_prefix_.data();
  double* const prefix_y = prefix_x + cols1;
  double* const prefix_z = prefix_y + cols1;
  std::uint32_t* const prefix_r = out.row_color_prefix_.data();
  std::uint32_t* const prefix_g = prefix_r + cols1;
  std::uint32_t* const prefix_b = prefix_g + cols1;

  // As geometry::backproject: the depth range on raw values, eqs 11-15 in float.
  const geometry::PixelTransform T(rays, frame, options);
  const std::uint32_t raw_min = T.raw_min, raw_max = T.raw_max;
  const float inv_factor = T.inv_factor;
  // As VoxelMap::insert: the voxel and the offset inside it, in voxel units.
  const float inv_voxel = static_cast<float>(1.0 / map.voxel_m());
  const bool colour = frame.bgr != nullptr;

  FrameVoxels::CacheSlot* const cache = out.cache_.data();
  std::uint64_t points = 0, dropped = 0;
  std::size_t considered = 0;
  for (int v = roi.y; v < roi.y + roi.height; v += s) {
    const geometry::FrameRow row(rays, frame, v);
    const std::uint16_t* drow = row.depth;
    const cv::Vec3b* crow = row.bgr;
    const std::uint8_t* mrow = row.mask;
    const float* rx = row.x_over_z;
    const float* ry = row.y_over_z;

    // 1. Each column's voxel and offsets (an invalid pixel's key is kNoVoxel).
    std::uint32_t row_points = 0, row_dropped = 0, row_considered = 0;
    int c0_scalar = 0;  // first column left to the scalar loop
#if defined(__SSE2__)
    if (s == 1) {
      // Four columns at a time: the scalar loop's float operations in the same order (the same
      // bits), without a branch per pixel (an invalid pixel's values are computed from 0 and
      // discarded). Keys are packed in two 64-bit lanes per half.
      const __m128 inv_f = _mm_set1_ps(inv_factor), inv_v = _mm_set1_ps(inv_voxel);
      const __m128i raw_lo = _mm_set1_epi32(static_cast<int>(raw_min) - 1);
      const __m128i raw_hi = _mm_set1_epi32(static_cast<int>(raw_max) + 1);
      const __m128i bias = _mm_set1_epi32(geometry::kVoxelCoordLimit);
      const __m128i zero = _mm_setzero_si128(), ones = _mm_set1_epi32(-1);
      __m128 Rm[9], Tv[3];
      for (int k = 0; k < 9; ++k) Rm[k] = _mm_set1_ps(T.r[k]);
      for (int k = 0; k < 3; ++k) Tv[k] = _mm_set1_ps(T.t[k]);
      for (; c0_scalar + 4 <= cols; c0_scalar += 4) {
        const int c = c0_scalar, u = roi.x + c;
        std::uint64_t raw4;
        std::memcpy(&raw4, drow + u, 8);
        const __m128i raw =
            _mm_unpacklo_epi16(_mm_cvtsi64_si128(static_cast<long long>(raw4)), zero);
        __m128i looked = ones;
        if (mrow) {
          std::uint32_t m4;
          std::memcpy(&m4, mrow + u, 4);
          const __m128i m = _mm_unpacklo_epi16(
              _mm_unpacklo_epi8(_mm_cvtsi32_si128(static_cast<int>(m4)), zero), zero);
          looked = _mm_xor_si128(_mm_cmpeq_epi32(m, zero), ones);
        }
        const __m128i depth_ok = _mm_and_si128(
            looked, _mm_and_si128(_mm_cmpgt_epi32(raw, raw_lo), _mm_cmplt_epi32(raw, raw_hi)));
        const __m128 z = _mm_mul_ps(_mm_cvtepi32_ps(raw), inv_f);
        const __m128 x = _mm_mul_ps(_mm_loadu_ps(rx + u), z);
        const __m128 y = _mm_mul_ps(_mm_loadu_ps(ry + u), z);
        const auto scaled = [&](int i) {  // (R · p + t)[i] / voxel size, as PixelTransform
          const __m128 w = _mm_add_ps(_mm_mul_ps(Rm[3 * i], x), _mm_mul_ps(Rm[3 * i + 1], y));
          return _mm_mul_ps(_mm_add_ps(_mm_add_ps(w, _mm_mul_ps(Rm[3 * i + 2], z)), Tv[i]), inv_v);
        };
        const geometry::VoxelCoords4 v4 = geometry::voxel_coords4(scaled(0), scaled(1), scaled(2));
        const __m128i ix = _mm_add_epi32(v4.ix, bias), iy = _mm_add_epi32(v4.iy, bias),
                      iz = _mm_add_epi32(v4.iz, bias);
        const __m128i valid = _mm_and_si128(depth_ok, _mm_castps_si128(v4.ok));
        const __m128 valid_ps = _mm_castsi128_ps(valid);  // offsets of invalid pixels: 0
        _mm_storeu_ps(off_x + c, _mm_and_ps(v4.fx, valid_ps));
        _mm_storeu_ps(off_y + c, _mm_and_ps(v4.fy, valid_ps));
        _mm_storeu_ps(off_z + c, _mm_and_ps(v4.fz, valid_ps));
        const auto keys = [&](__m128i a, __m128i b, __m128i cc, __m128i v) {  // 2 lanes
          const __m128i k =
              _mm_or_si128(_mm_or_si128(_mm_slli_epi64(a, 42), _mm_slli_epi64(b, 21)), cc);
          return _mm_or_si128(k, _mm_xor_si128(v, ones));  // invalid: all ones (kNoVoxel)
        };
        _mm_storeu_si128(reinterpret_cast<__m128i*>(key_now + c),
                         keys(_mm_unpacklo_epi32(ix, zero), _mm_unpacklo_epi32(iy, zero),
                              _mm_unpacklo_epi32(iz, zero), _mm_unpacklo_epi32(valid, valid)));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(key_now + c + 2),
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
    }
#endif
    for (int c = c0_scalar; c < cols; ++c) {
      const int u = roi.x + c * s;
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
    considered += row_considered;
    points += row_points;
    dropped += row_dropped;

    // 2. The row's runs: the columns where the key changes, found without a branch per pixel, and
    //    prefix sums of the offsets (in double: a difference is exact to ~1e-13) and colours, so
    //    that a run's sums are subtractions.
    int runs = 0;
    {
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
          const cv::Vec3b& bgr = crow[roi.x + c * s];
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
    }
    // 3. Each run of a voxel added to the voxel's entry: the one the cache holds for the voxel, or
    //    a new one (the cache slot then points to it).
    for (int r = 0; r < runs; ++r) {
      const int first = starts[r], end = starts[r + 1];
      const VoxelKey key = key_now[first];
      if (key == kNoVoxel) continue;
      FrameVoxels::CacheSlot& slot = cache[FrameVoxels::cache_slot(key)];
      FrameVoxels::Entry* e;
      if (slot.key == key) {
        e = &out.shards_[slot.shard][slot.index];
      } else {
        const std::size_t sh = map.shard_of(key);
        std::vector<FrameVoxels::Entry>& entries = out.shards_[sh];
        slot.key = key;
        slot.shard = static_cast<std::uint32_t>(sh);
        slot.index = static_cast<std::uint32_t>(entries.size());
        e = &entries.emplace_back();
        e->key = key;
      }
      VoxelData& sum = e->sum;
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
