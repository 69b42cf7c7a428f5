#pragma once
// voxel_coords() (voxel_key.h) on four points at once with SSE2, for the loops that key every point
// of a frame: the scalar code's float operations in the same order, so the same bits.
#if defined(__SSE2__)
#include <emmintrin.h>

#include "objmap/geometry/voxel_key.h"

namespace objmap::geometry {

struct VoxelCoords4 {
  __m128i ix, iy, iz;  // voxel coordinates (0 where out of range)
  __m128 fx, fy, fz;   // offsets inside the voxel in voxel units, in [0, 1) (0 where out of range)
  __m128 ok;           // all ones where the point is in the key range (NaN is not)
};

// sx, sy, sz: four points' coordinates / voxel size. Out-of-range lanes are computed from 0, as
// the scalar loops do (no float-to-int conversion of NaN or huge values).
inline VoxelCoords4 voxel_coords4(__m128 sx, __m128 sy, __m128 sz) {
  constexpr float lim = static_cast<float>(kVoxelCoordLimit);
  const __m128 lo = _mm_set1_ps(-lim), hi = _mm_set1_ps(lim);
  VoxelCoords4 c;
  c.ok = _mm_and_ps(_mm_cmpge_ps(sx, lo), _mm_cmplt_ps(sx, hi));
  c.ok = _mm_and_ps(c.ok, _mm_and_ps(_mm_cmpge_ps(sy, lo), _mm_cmplt_ps(sy, hi)));
  c.ok = _mm_and_ps(c.ok, _mm_and_ps(_mm_cmpge_ps(sz, lo), _mm_cmplt_ps(sz, hi)));
  const auto floor4 = [&](__m128 v, __m128i& cell) {  // fast_floor on 4 lanes; returns the offset
    v = _mm_and_ps(v, c.ok);
    const __m128i t = _mm_cvttps_epi32(v);
    const __m128i below = _mm_castps_si128(_mm_cmplt_ps(v, _mm_cvtepi32_ps(t)));
    cell = _mm_add_epi32(t, below);  // t - 1 where v < t
    return _mm_sub_ps(v, _mm_cvtepi32_ps(cell));
  };
  c.fx = floor4(sx, c.ix);
  c.fy = floor4(sy, c.iy);
  c.fz = floor4(sz, c.iz);
  return c;
}

}  // namespace objmap::geometry
#endif
