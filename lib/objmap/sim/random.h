#pragma once
#include <cmath>
#include <cstdint>

// A small, portable random generator (SplitMix64) with its own uniform and normal draws, so that
// the synthetic sequences are byte-identical across standard libraries (std::normal_distribution is
// not).
namespace objmap::sim {

// Mixes a 64-bit value (SplitMix64 finaliser); also used to derive independent seeds.
inline std::uint64_t mix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Seed of stream `stream` (e.g. a frame index) of the generator seeded with `seed`.
inline std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t stream, std::uint64_t salt = 0) {
  return mix64(mix64(seed ^ (salt * 0xD1B54A32D192ED03ull)) + stream);
}

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(mix64(seed)) {}
  std::uint64_t next() {
    state_ += 0x9E3779B97F4A7C15ull;
    std::uint64_t z = state_;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1).
  double uniform() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // Uniform integer in [0, n).
  int uniform_int(int n) { return static_cast<int>(uniform() * n); }
  // Standard normal (Box-Muller, both values used).
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u1 = uniform();
    while (u1 <= 0.0) u1 = uniform();
    const double u2 = uniform();
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(2.0 * M_PI * u2);
    has_spare_ = true;
    return r * std::cos(2.0 * M_PI * u2);
  }
  double normal(double mean, double sigma) { return mean + sigma * normal(); }
  // Cheap approximately normal draw (Irwin-Hall: sum of four 16-bit uniforms, unit variance, tails
  // cut at +-3.46): for image noise, where millions of draws are needed per frame.
  double fast_normal() {
    const std::uint64_t x = next();
    const double sum = static_cast<double>((x & 0xFFFF) + ((x >> 16) & 0xFFFF) +
                                           ((x >> 32) & 0xFFFF) + (x >> 48)) *
                       (1.0 / 65536.0);
    return (sum - 2.0) * 1.7320508075688772;  // sqrt(12 / 4)
  }
  // Poisson count with mean `lambda` (inversion; lambda is small here).
  int poisson(double lambda) {
    const double l = std::exp(-lambda);
    int k = 0;
    double p = uniform();
    while (p > l && k < 1000) {
      p *= uniform();
      ++k;
    }
    return k;
  }

 private:
  std::uint64_t state_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace objmap::sim
