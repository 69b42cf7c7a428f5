#pragma once
// The outlier filter's benchmark clouds, shared by bench_fusion.cpp and compare_pcl_sor.cpp.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <map>
#include <random>
#include <tuple>

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

// An object's record as fuse filters it: one point per occupied 1 cm voxel (the mean of dense
// surface samples in it) of a 40 x 40 x 80 cm box's top and four sides, 1 mm noise, and 1 % of
// the voxels' points moved 1-5 cm off the surface (mixed pixels): ~14k points.
inline PointCloud voxel_record_cloud() {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> uni(0.f, 1.f);
  std::normal_distribution<float> noise(0.f, 0.001f);
  std::map<std::tuple<int, int, int>, std::pair<Vec3f, int>> voxels;
  auto add = [&](Vec3f p) {
    p += Vec3f(noise(rng), noise(rng), noise(rng));
    auto& v = voxels
                  .try_emplace({static_cast<int>(std::floor(p.x() * 100)),
                                static_cast<int>(std::floor(p.y() * 100)),
                                static_cast<int>(std::floor(p.z() * 100))},
                               Vec3f::Zero(), 0)
                  .first->second;
    v.first += p;
    ++v.second;
  };
  for (int i = 0; i < 400000; ++i) {
    const float a = uni(rng), b = uni(rng);
    switch (i % 5) {
      case 0:
        add(Vec3f(0.4f * a, 0.4f * b, 0.8f));
        break;  // top
      case 1:
        add(Vec3f(0.4f * a, 0.f, 0.8f * b));
        break;  // sides
      case 2:
        add(Vec3f(0.4f * a, 0.4f, 0.8f * b));
        break;
      case 3:
        add(Vec3f(0.f, 0.4f * a, 0.8f * b));
        break;
      default:
        add(Vec3f(0.4f, 0.4f * a, 0.8f * b));
        break;
    }
  }
  PointCloud c;
  for (const auto& [key, v] : voxels) {
    Vec3f p = v.first / static_cast<float>(v.second);
    if (uni(rng) < 0.01f) p += Vec3f(uni(rng) - 0.5f, uni(rng) - 0.5f, uni(rng) - 0.5f) * 0.1f;
    c.push_back(p, Rgb{100, 120, 140});
  }
  return c;
}

}  // namespace objmap::bench
