#pragma once
// The outlier filter's benchmark cloud, shared by bench_fusion.cpp and compare_pcl_sor.cpp.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>

#include "objmap/core/types.h"

namespace objmap::bench {

// A surface-like cloud of n points (noisy sphere patches) with 0.5% scattered outliers.
inline PointCloud surface_cloud(std::size_t n) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> uni(0.f, 1.f);
  std::normal_distribution<float> noise(0.f, 0.002f);
  PointCloud c;
  c.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (i % 200 == 199) {
      c.push_back(Vec3f(uni(rng) * 3, uni(rng) * 3, uni(rng) * 3), Rgb{1, 2, 3});
      continue;
    }
    const float th = uni(rng) * 3.14159f, ph = uni(rng) * 6.28318f;
    c.push_back(Vec3f(1.5f + 0.5f * std::sin(th) * std::cos(ph) + noise(rng),
                      1.5f + 0.5f * std::sin(th) * std::sin(ph) + noise(rng),
                      1.5f + 0.5f * std::cos(th) + noise(rng)),
                Rgb{static_cast<std::uint8_t>(i), 100, 200});
  }
  return c;
}

}  // namespace objmap::bench
