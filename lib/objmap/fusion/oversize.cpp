#include "objmap/fusion/oversize.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>

#include <Eigen/Eigenvalues>

#include "objmap/core/error.h"

namespace objmap::fusion {

namespace {

// Two unit vectors that span the plane perpendicular to `up`.
std::pair<Vec3, Vec3> horizontal_basis(const Vec3& up) {
  const Vec3 n = up.normalized();
  const Vec3 seed = std::fabs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 e1 = (seed - seed.dot(n) * n).normalized();
  return {e1, n.cross(e1)};
}

// The nearest rank of the q-quantile among n > 0 values.
std::size_t quantile_rank(std::size_t n, double q) {
  const auto k = static_cast<std::size_t>(std::lround(q * static_cast<double>(n - 1)));
  return std::min(k, n - 1);
}

// The q-quantile of sorted values (nearest rank).
double quantile(const std::vector<double>& sorted, double q) {
  return sorted[quantile_rank(sorted.size(), q)];
}

// quantile() of `values` sorted, at q and at 1 - q: the same two order statistics, found by two
// selections rather than a sort (`values` is reordered; empty: zeros).
std::pair<double, double> quantile_pair(std::vector<double>& values, double q) {
  const std::size_t n = values.size();
  if (n == 0) return {0.0, 0.0};
  const std::size_t a = quantile_rank(n, q), b = quantile_rank(n, 1.0 - q);
  const auto at = [&values](std::size_t k) {
    return values.begin() + static_cast<std::ptrdiff_t>(k);
  };
  std::nth_element(values.begin(), at(std::max(a, b)), values.end());
  if (a != b) std::nth_element(values.begin(), at(std::min(a, b)), at(std::max(a, b)));
  return {values[a], values[b]};
}

// The profile of sorted values `along` between lo and hi, in bins of about bin_m (smoothed over
// ±smooth_bins), and its emptiest bin whose centre lies in [from, to] (the one nearest the middle
// among equals; the middle bin when none does): where it lies, which side holds more, and whether
// it parts two instances (each side at least min_side_share of the values, the bin at most
// valley_ratio × the sparser side's mean).
struct Valley {
  double at = 0.0;
  int keep = 0;
  bool apart = false;
};
Valley emptiest_place(const std::vector<double>& along, double lo, double hi, double from,
                      double to, double valley_ratio, const OversizeOptions& o) {
  const int bins = std::max(3, static_cast<int>(std::ceil((hi - lo) / o.bin_m)));
  const double bin = (hi - lo) / bins;
  std::vector<double> count(bins, 0.0);
  for (double a : along)
    if (a >= lo && a <= hi) ++count[std::min(bins - 1, static_cast<int>((a - lo) / bin))];
  std::vector<double> smooth(bins, 0.0);
  for (int b = 0; b < bins; ++b) {
    int n = 0;
    for (int k = std::max(0, b - o.smooth_bins); k <= std::min(bins - 1, b + o.smooth_bins); ++k) {
      smooth[b] += count[k];
      ++n;
    }
    smooth[b] /= n;
  }
  int best = -1;
  for (int b = 0; b < bins; ++b) {
    const double at = lo + (b + 0.5) * bin;
    if (at < from - 0.5 * bin || at > to + 0.5 * bin) continue;
    const double middle = std::fabs(b + 0.5 - 0.5 * bins);
    if (best < 0 || smooth[b] < smooth[best] ||
        (smooth[b] == smooth[best] && middle < std::fabs(best + 0.5 - 0.5 * bins)))
      best = b;
  }
  if (best < 0) best = bins / 2;
  Valley v;
  v.at = lo + (best + 0.5) * bin;
  // The sides' shares of the values and mean densities (the bin itself on neither side).
  std::array<double, 2> mass{0.0, 0.0}, width{0.0, 0.0};
  for (int b = 0; b < bins; ++b) {
    if (b == best) continue;
    mass[b < best ? 0 : 1] += count[b];
    width[b < best ? 0 : 1] += 1.0;
  }
  const double total = mass[0] + mass[1] + count[best];
  const double weaker_density =
      std::min(mass[0] / std::max(1.0, width[0]), mass[1] / std::max(1.0, width[1]));
  v.keep = mass[1] > mass[0] ? 1 : 0;
  v.apart = total > 0.0 && std::min(mass[0], mass[1]) >= o.min_side_share * total &&
            count[best] <= valley_ratio * weaker_density;
  return v;
}

// The band [from, from + width) of sorted values `along` (from within [lo, hi], its centre within
// [first, last], in steps of width / 2) holding the fewest values: a gap between two parts must
// be empty at the points' own spacing; bins of fixed phase would count a wall beside the gap in
// the gap's bin, and a smoothed profile would hide a gap narrower than the smoothing.
struct Band {
  double from = 0.0;
  double count = 0.0;
};
Band emptiest_band(const std::vector<double>& along, double lo, double hi, double first,
                   double last, double width) {
  Band best;
  best.count = -1.0;
  const double start = std::max(lo, first - 0.5 * width);
  const double end = std::min(hi - width, last - 0.5 * width);
  for (double from = start; from <= end + 1e-12; from += 0.5 * width) {
    const double n =
        static_cast<double>(std::lower_bound(along.begin(), along.end(), from + width) -
                            std::lower_bound(along.begin(), along.end(), from));
    if (best.count < 0.0 || n < best.count) best = {from, n};
  }
  if (best.count < 0.0) best = {0.5 * (lo + hi - width), 1e300};
  return best;
}

}  // namespace

void OversizeOptions::check() const {
  require(margin >= 0.0 && margin <= 10.0, "OversizeOptions.margin", "must be in [0, 10]");
  require(percentile >= 0.0 && percentile < 0.5, "OversizeOptions.percentile",
          "must be in [0, 0.5)");
  require(bin_m > 0.0 && bin_m <= 1.0, "OversizeOptions.bin_m", "must be in (0, 1] m");
  require(smooth_bins >= 0 && smooth_bins <= 50, "OversizeOptions.smooth_bins",
          "must be in [0, 50]");
  require(valley_ratio >= 0.0 && valley_ratio <= 1.0, "OversizeOptions.valley_ratio",
          "must be in [0, 1]");
  require(min_side_share >= 0.0 && min_side_share <= 0.5, "OversizeOptions.min_side_share",
          "must be in [0, 0.5]");
  require(flat_m >= 0.0 && flat_share >= 0.0, "OversizeOptions.flat_m", "must be >= 0");
  require(join_gap_m >= 0.0 && join_gap_m <= 10.0, "OversizeOptions.join_gap_m",
          "must be in [0, 10] m");
  require(join_grow_m >= 0.0 && join_grow_m <= 10.0, "OversizeOptions.join_grow_m",
          "must be in [0, 10] m");
  require(join_min_inside >= 0.0 && join_min_inside <= 1.0, "OversizeOptions.join_min_inside",
          "must be in [0, 1]");
  require(join_valley_ratio >= 0.0 && join_valley_ratio <= 1.0, "OversizeOptions.join_valley_ratio",
          "must be in [0, 1]");
  require(under_gap_m >= 0.0 && under_gap_m <= 10.0, "OversizeOptions.under_gap_m",
          "must be in [0, 10] m");
  require(rename_min_vote >= 0.0 && rename_min_vote <= 1.0, "OversizeOptions.rename_min_vote",
          "must be in [0, 1]");
}

double horizontal_extent(const std::vector<Vec3>& surface, const Vec3& up, double percentile,
                         Vec3* axis) {
  if (surface.size() < 2) return 0.0;
  const auto [e1, e2] = horizontal_basis(up);
  // The long axis: the principal axis of the horizontal projections.
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const Vec3& p : surface) mean += Eigen::Vector2d(e1.dot(p), e2.dot(p));
  mean /= static_cast<double>(surface.size());
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const Vec3& p : surface) {
    const Eigen::Vector2d d = Eigen::Vector2d(e1.dot(p), e2.dot(p)) - mean;
    cov += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
  const Eigen::Vector2d major = eig.eigenvectors().col(1);
  Vec3 long_axis = (major.x() * e1 + major.y() * e2).normalized();
  // A fixed sign, so that the same surface gives the same axis whatever its order.
  if (long_axis.x() + 1e-9 * long_axis.y() < 0.0) long_axis = -long_axis;
  std::vector<double> along;
  along.reserve(surface.size());
  for (const Vec3& p : surface) along.push_back(long_axis.dot(p));
  if (axis) *axis = long_axis;
  const auto [lo, hi] = quantile_pair(along, percentile);
  return hi - lo;
}

std::optional<OversizeCut> plan_oversize_cut(const std::vector<Vec3>& surface, const Vec3& up,
                                             double min_m, double max_m, const OversizeOptions& o,
                                             bool* tall_beyond) {
  if (tall_beyond) *tall_beyond = false;
  if (!o.enabled || surface.size() < 10 || !(max_m > 0.0)) return std::nullopt;
  OversizeCut cut;
  cut.extent_m = horizontal_extent(surface, up, o.percentile, &cut.axis);
  cut.limit_m = max_m * (1.0 + o.margin);
  if (cut.extent_m <= cut.limit_m) return std::nullopt;
  // 1-3. The emptiest place of the profile along the long axis where both sides are at least
  //      min_m wide (half the extent at most), and whether it parts two instances.
  std::vector<double> along;
  for (const Vec3& p : surface) along.push_back(cut.axis.dot(p));
  std::sort(along.begin(), along.end());
  const double lo = quantile(along, o.percentile), hi = quantile(along, 1.0 - o.percentile);
  const double side = std::min(min_m, 0.5 * (hi - lo));
  const Valley valley = emptiest_place(along, lo, hi, lo + side, hi - side, o.valley_ratio, o);
  cut.cut = valley.at;
  cut.keep = valley.keep;
  cut.apart = valley.apart;
  if (cut.apart) return cut;
  // 4. One instance: what is cut off must be a flat strip (the table or floor its masks held),
  //    its heights within max(flat_m, flat_share × the kept side's); anything taller is part of
  //    the object (a monitor that the detector named "laptop"), and nothing is cut.
  std::array<std::vector<double>, 2> heights;
  const Vec3 n = up.normalized();
  for (const Vec3& p : surface) heights[cut.axis.dot(p) < cut.cut ? 0 : 1].push_back(n.dot(p));
  std::array<double, 2> span{0.0, 0.0};
  for (int k = 0; k < 2; ++k) {
    if (heights[k].size() < 2) continue;
    const auto [lo, hi] = quantile_pair(heights[k], o.percentile);
    span[k] = hi - lo;
  }
  if (span[1 - cut.keep] > std::max(o.flat_m, o.flat_share * span[cut.keep])) {
    if (!tall_beyond) return std::nullopt;
    *tall_beyond = true;
  }
  return cut;
}

Footprint footprint(const std::vector<Vec3>& surface, const Vec3& up, double percentile) {
  Footprint f;
  horizontal_extent(surface, up, percentile, &f.axes[0]);
  f.axes[2] = up.normalized();
  f.axes[1] = f.axes[2].cross(f.axes[0]).normalized();
  if (surface.empty()) return f;
  std::vector<double> along(surface.size());
  for (int k = 0; k < 3; ++k) {
    for (std::size_t i = 0; i < surface.size(); ++i) along[i] = f.axes[k].dot(surface[i]);
    std::tie(f.lo[k], f.hi[k]) = quantile_pair(along, percentile);
  }
  return f;
}

PartsFit fit_parts(const std::vector<Vec3>& small, const std::vector<Vec3>& large,
                   const Footprint& lf, const Vec3& up, double percentile, double grow_m) {
  PartsFit fit;
  if (small.empty() || large.empty()) return fit;
  std::size_t inside = 0;
  std::array<std::vector<double>, 3> at;
  for (const Vec3& p : small) {
    bool in = true;
    for (int k = 0; k < 3; ++k) {
      at[k].push_back(lf.axes[k].dot(p));
      if (k < 2) in = in && at[k].back() >= lf.lo[k] - grow_m && at[k].back() <= lf.hi[k] + grow_m;
    }
    inside += in;
  }
  fit.inside_share = static_cast<double>(inside) / static_cast<double>(small.size());
  double gap2 = 0.0;
  for (int k = 0; k < 3; ++k) {
    const auto [lo, hi] = quantile_pair(at[k], percentile);
    const double gap = std::max({0.0, lo - lf.hi[k], lf.lo[k] - hi});
    gap2 += gap * gap;
  }
  fit.gap_m = std::sqrt(gap2);
  std::vector<Vec3> both = large;
  both.insert(both.end(), small.begin(), small.end());
  fit.union_extent_m = horizontal_extent(both, up, percentile);
  return fit;
}

bool continuous_parts(const std::vector<Vec3>& a, const std::vector<Vec3>& b, const Vec3& up,
                      const OversizeOptions& o) {
  if (a.size() < 10 || b.size() < 10) return false;
  std::vector<Vec3> both = b;
  both.insert(both.end(), a.begin(), a.end());
  Vec3 axis;
  horizontal_extent(both, up, o.percentile, &axis);
  const auto middle = [&](const std::vector<Vec3>& part) {
    std::vector<double> at;
    for (const Vec3& p : part) at.push_back(axis.dot(p));
    std::nth_element(at.begin(), at.begin() + static_cast<std::ptrdiff_t>(at.size() / 2), at.end());
    return at[at.size() / 2];
  };
  const double ma = middle(a), mb = middle(b);
  std::vector<double> along;
  for (const Vec3& p : both) along.push_back(axis.dot(p));
  std::sort(along.begin(), along.end());
  const double lo = quantile(along, o.percentile), hi = quantile(along, 1.0 - o.percentile);
  const Band band = emptiest_band(along, lo, hi, std::min(ma, mb), std::max(ma, mb), o.bin_m);
  const auto count_in = [&](double from, double to) {
    return static_cast<double>(std::lower_bound(along.begin(), along.end(), to) -
                               std::lower_bound(along.begin(), along.end(), from));
  };
  // Each side's mean count per band width, and its share of what lies in [lo, hi].
  const double left = count_in(lo, band.from), right = count_in(band.from + o.bin_m, hi);
  const double total = count_in(lo, hi);
  const double sparser = std::min(left / std::max(o.bin_m, band.from - lo),
                                  right / std::max(o.bin_m, hi - band.from - o.bin_m)) *
                         o.bin_m;
  const bool gap = total > 0.0 && std::min(left, right) >= o.min_side_share * total &&
                   band.count <= o.join_valley_ratio * sparser;
  return !gap;
}

}  // namespace objmap::fusion
