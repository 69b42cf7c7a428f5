#include "objmap/sim/texture.h"

#include <algorithm>
#include <cmath>

namespace objmap::sim {

namespace {

// A fixed permutation of 0..255 (Perlin-style lattice hash), built once from a fixed seed.
struct Permutation {
  std::uint8_t p[512];
  float value[256];
  Permutation() {
    std::uint64_t state = 0x243F6A8885A308D3ull;
    auto next = [&state] {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      return static_cast<std::uint32_t>(state >> 33);
    };
    std::uint8_t perm[256];
    for (int i = 0; i < 256; ++i) perm[i] = static_cast<std::uint8_t>(i);
    for (int i = 255; i > 0; --i) std::swap(perm[i], perm[next() % (i + 1)]);
    for (int i = 0; i < 512; ++i) p[i] = perm[i & 255];
    for (int i = 0; i < 256; ++i) value[i] = static_cast<float>(next() % 100000) / 100000.0f;
  }
};
const Permutation& permutation() {
  static const Permutation table;
  return table;
}

// floor() without the library call (the build targets baseline x86-64, which has no rounding
// instruction): exact for |x| < 2^52. It gives +0 for -0, which changes nothing below (the fraction
// only scales differences of lattice values).
inline double floor_fast(double x) {
  if (!(std::abs(x) < 4503599627370496.0)) return std::floor(x);
  const double t = static_cast<double>(static_cast<std::int64_t>(x));
  return t > x ? t - 1.0 : t;
}

double smooth(double t) { return t * t * (3.0 - 2.0 * t); }

Eigen::Vector3d to_vec(const Rgb& c) { return Eigen::Vector3d(c.r, c.g, c.b) / 255.0; }

}  // namespace

double value_noise(const Vec3& p, std::uint32_t seed) {
  const double fx = floor_fast(p.x()), fy = floor_fast(p.y()), fz = floor_fast(p.z());
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy),
             iz = static_cast<std::int64_t>(fz);
  const double tx = smooth(p.x() - fx), ty = smooth(p.y() - fy), tz = smooth(p.z() - fz);
  // Lattice hash of the 8 corners (Perlin-style: x, then y, then z, then the seed's top byte),
  // sharing the x and xy levels between corners. The seed shifts the lattice so that different
  // materials get different patterns.
  const auto& t = permutation();
  const std::int64_t sx = ix + seed, sy = iy + (seed >> 8), sz = iz + (seed >> 16);
  const int sw = static_cast<int>((seed >> 24) & 255);
  double c[2][2][2];
  for (int a = 0; a < 2; ++a) {
    const int ha = t.p[(sx + a) & 255];
    for (int b = 0; b < 2; ++b) {
      const int hb = t.p[(ha + sy + b) & 255];
      for (int d = 0; d < 2; ++d) c[a][b][d] = t.value[t.p[t.p[(hb + sz + d) & 255] + sw]];
    }
  }
  auto lerp = [](double u, double v, double t) { return u + (v - u) * t; };
  const double x00 = lerp(c[0][0][0], c[1][0][0], tx), x10 = lerp(c[0][1][0], c[1][1][0], tx);
  const double x01 = lerp(c[0][0][1], c[1][0][1], tx), x11 = lerp(c[0][1][1], c[1][1][1], tx);
  return lerp(lerp(x00, x10, ty), lerp(x01, x11, ty), tz);
}

double fractal_noise(const Vec3& p, std::uint32_t seed) {
  double sum = 0.0, amplitude = 0.5, norm = 0.0;
  Vec3 q = p;
  for (int octave = 0; octave < 3; ++octave) {
    sum += amplitude * value_noise(q, seed + 101u * static_cast<std::uint32_t>(octave));
    norm += amplitude;
    amplitude *= 0.5;
    q *= 2.03;
  }
  return sum / norm;
}

Eigen::Vector3d albedo(const Material& m, const Vec3& p) {
  const Eigen::Vector3d base = to_vec(m.base);
  const Eigen::Vector3d accent = to_vec(m.accent);
  const double s = m.scale_m > 0.0 ? m.scale_m : 0.02;
  double w = 0.0;  // blend weight towards the accent colour
  switch (m.pattern) {
    case Pattern::kSolid:
      w = 0.0;
      break;
    case Pattern::kChecker: {
      const auto i = static_cast<std::int64_t>(floor_fast(p.x() / s)) +
                     static_cast<std::int64_t>(floor_fast(p.y() / s)) +
                     static_cast<std::int64_t>(floor_fast(p.z() / s));
      w = (i & 1) ? 1.0 : 0.0;
      break;
    }
    case Pattern::kStripes:
      w = (static_cast<std::int64_t>(floor_fast(p.z() / s)) & 1) ? 1.0 : 0.0;
      break;
    case Pattern::kNoise: {
      const double n = fractal_noise(p / s, m.seed);
      w = std::clamp((n - 0.5) * 2.2 + 0.5, 0.0, 1.0);
      break;
    }
    case Pattern::kKeys: {
      const double fx = p.x() / s - floor_fast(p.x() / s);
      const double fy = p.y() / s - floor_fast(p.y() / s);
      w = (fx > 0.12 && fx < 0.88 && fy > 0.12 && fy < 0.88) ? 1.0 : 0.0;
      break;
    }
  }
  Eigen::Vector3d c = base + w * (accent - base);
  if (m.grain > 0.0 && m.pattern != Pattern::kNoise) {  // noise patterns have their own detail
    const double g = value_noise(p / 0.004, m.seed ^ 0x5bd1e995u) - 0.5;
    c *= 1.0 + 2.0 * m.grain * g;
  }
  return c.cwiseMax(0.0).cwiseMin(1.0);
}

}  // namespace objmap::sim
