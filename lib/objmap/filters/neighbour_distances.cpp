#include "objmap/filters/neighbour_distances.h"

#include <flann/flann.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>

#include "objmap/core/error.h"
#include "objmap/core/parallel.h"
#include "objmap/geometry/voxel_key.h"

namespace objmap::filters {
namespace {

// FLANN's L2_Simple<float>: diff = query - point, result += diff * diff over x, y, z from 0. The
// grid search computes every distance this way, so its distances are the kd-tree's, bit for bit.
inline float flann_squared_distance(const float* q, float px, float py, float pz) {
  const float dx = q[0] - px, dy = q[1] - py, dz = q[2] - pz;
  float r = dx * dx;
  r += dy * dy;
  r += dz * dz;
  return r;
}

// d_i from the k + 1 nearest squared distances, nearest first (the first is the point itself).
inline double mean_of_nearest(const float* sorted_sq, int k) {
  double sum = 0.0;
  for (int j = 1; j <= k; ++j) sum += std::sqrt(static_cast<double>(sorted_sq[j]));
  return sum / static_cast<double>(k);
}

// ---------------------------------------------------------------------------------------------
// The kd-tree (FLANN's single index, as PCL's KdTreeFLANN builds it).

class KdTree {
 public:
  explicit KdTree(const PointCloud& cloud)
      : data_(const_cast<float*>(cloud.points.front().data()), cloud.size(), 3),
        tree_(data_, flann::KDTreeSingleIndexParams(15)) {
    static_assert(sizeof(Vec3f) == 3 * sizeof(float), "points must be packed xyz floats");
    tree_.buildIndex();
  }
  // The k + 1 nearest squared distances of `rows` query points (xyz floats), nearest first.
  void search(const float* queries, std::size_t rows, int k, std::vector<int>& idx,
              std::vector<float>& sq) {
    const std::size_t kk = static_cast<std::size_t>(k) + 1;
    idx.resize(rows * kk);
    sq.resize(rows * kk);
    flann::Matrix<float> q(const_cast<float*>(queries), rows, 3);
    flann::Matrix<int> idx_m(idx.data(), rows, kk);
    flann::Matrix<float> sq_m(sq.data(), rows, kk);
    tree_.knnSearch(q, idx_m, sq_m, kk, flann::SearchParams(-1, 0.0f, /*sorted=*/true));
  }

 private:
  flann::Matrix<float> data_;
  flann::Index<flann::L2_Simple<float>> tree_;
};

// d_i of the points `which` (indices into the cloud) from the kd-tree, 4096 queries per call.
void kdtree_distances(const PointCloud& cloud, const std::vector<std::uint32_t>& which, int k,
                      int threads, std::vector<double>& out) {
  if (which.empty()) return;
  KdTree tree(cloud);
  constexpr std::size_t kBlock = 4096;
  const std::size_t blocks = (which.size() + kBlock - 1) / kBlock;
  const std::size_t kk = static_cast<std::size_t>(k) + 1;
  parallel_for(blocks, threads, [&](std::size_t b) {
    const std::size_t begin = b * kBlock, rows = std::min(kBlock, which.size() - begin);
    std::vector<float> queries(rows * 3);
    for (std::size_t r = 0; r < rows; ++r)
      std::copy_n(cloud.points[which[begin + r]].data(), 3, queries.data() + 3 * r);
    std::vector<int> idx;
    std::vector<float> sq;
    tree.search(queries.data(), rows, k, idx, sq);
    for (std::size_t r = 0; r < rows; ++r) out[which[begin + r]] = mean_of_nearest(&sq[r * kk], k);
  });
}

// ---------------------------------------------------------------------------------------------
// The grid: the points sorted by cell (x, then y, then z), each cell's range found by its key.

// Cell indices count from the grid's origin, 0 .. 2^21 - 1 on each axis; a cell's key is its
// geometry::VoxelKey (3 x 21 bits, so sorting keys sorts by x, then y, then z).
constexpr std::int64_t kAxisCells = 2 * std::int64_t{geometry::kVoxelCoordLimit};
constexpr int kWidestRing = 4;  // rings searched before the kd-tree

std::uint64_t cell_key(std::int64_t x, std::int64_t y, std::int64_t z) {
  const auto centred = [](std::int64_t i) {
    return static_cast<std::int32_t>(i - geometry::kVoxelCoordLimit);
  };
  return geometry::pack_voxel(centred(x), centred(y), centred(z));
}

struct Grid {
  double cell = 0.0;
  double origin[3] = {0, 0, 0};
  std::vector<std::uint64_t> keys;   // occupied cells, ascending
  std::vector<std::uint32_t> begin;  // keys.size() + 1 offsets into the arrays below
  std::vector<std::uint32_t> index;  // the cloud's index of each point, by cell
  std::vector<float> xyz;            // the points, by cell

  std::int64_t axis_cell(float v, int axis) const {
    const double c = std::floor((static_cast<double>(v) - origin[axis]) / cell);
    return std::clamp<std::int64_t>(static_cast<std::int64_t>(c), 0, kAxisCells - 1);
  }
  // Cells [first, last) of column (x, y) with z in [z0, z1].
  std::pair<std::size_t, std::size_t> column(std::int64_t x, std::int64_t y, std::int64_t z0,
                                             std::int64_t z1) const {
    const auto lo = std::lower_bound(keys.begin(), keys.end(), cell_key(x, y, z0));
    const auto hi = std::upper_bound(lo, keys.end(), cell_key(x, y, z1));
    return {static_cast<std::size_t>(lo - keys.begin()),
            static_cast<std::size_t>(hi - keys.begin())};
  }
};

Grid build_grid(const PointCloud& cloud, double cell, const Eigen::Vector3d& lo) {
  Grid g;
  g.cell = cell;
  for (int a = 0; a < 3; ++a) g.origin[a] = lo[a] - cell;  // one empty cell below every point
  const std::size_t n = cloud.size();
  std::vector<std::pair<std::uint64_t, std::uint32_t>> sorted(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3f& p = cloud.points[i];
    sorted[i] = {cell_key(g.axis_cell(p.x(), 0), g.axis_cell(p.y(), 1), g.axis_cell(p.z(), 2)),
                 static_cast<std::uint32_t>(i)};
  }
  std::sort(sorted.begin(), sorted.end());
  g.index.resize(n);
  g.xyz.resize(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    if (i == 0 || sorted[i].first != sorted[i - 1].first) {
      g.keys.push_back(sorted[i].first);
      g.begin.push_back(static_cast<std::uint32_t>(i));
    }
    g.index[i] = sorted[i].second;
    std::copy_n(cloud.points[sorted[i].second].data(), 3, &g.xyz[3 * i]);
  }
  g.begin.push_back(static_cast<std::uint32_t>(n));
  return g;
}

// One query's search through the cells up to `ring` cells away from its own. The query is settled
// when its (k+1)-th nearest candidate is nearer than any point outside those cells can be.
class RingSearch {
 public:
  RingSearch(const Grid& g, int k) : g_(g), k_(k) {}

  // Gathers the points of the cells up to `ring` away from cell (x, y, z).
  void gather(std::int64_t x, std::int64_t y, std::int64_t z, int ring) {
    cx_.clear();
    cy_.clear();
    cz_.clear();
    const std::int64_t z0 = std::max<std::int64_t>(0, z - ring);
    const std::int64_t z1 = std::min(kAxisCells - 1, z + ring);
    for (std::int64_t ix = std::max<std::int64_t>(0, x - ring);
         ix <= std::min(kAxisCells - 1, x + ring); ++ix)
      for (std::int64_t iy = std::max<std::int64_t>(0, y - ring);
           iy <= std::min(kAxisCells - 1, y + ring); ++iy) {
        const auto [c0, c1] = g_.column(ix, iy, z0, z1);
        for (std::size_t p = g_.begin[c0]; p < g_.begin[c1]; ++p) {
          cx_.push_back(g_.xyz[3 * p]);
          cy_.push_back(g_.xyz[3 * p + 1]);
          cz_.push_back(g_.xyz[3 * p + 2]);
        }
      }
  }

  // d_i of the point at `q` in cell (x, y, z) from the gathered cells (`ring` away), or false when
  // a point outside them could be among its k + 1 nearest.
  bool settle(const float* q, const std::int64_t cell[3], int ring, double& mean) {
    // The nearest any point outside the searched cells can be: `ring` cells plus the query's
    // distance to its own cell's nearest face, less a margin for the rounding of the cell index
    // and of the float distances.
    double margin = g_.cell;
    for (int a = 0; a < 3; ++a) {
      const double low = g_.origin[a] + static_cast<double>(cell[a]) * g_.cell;
      const double v = static_cast<double>(q[a]);
      margin = std::min({margin, v - low, low + g_.cell - v});
    }
    const double reach = (ring * g_.cell + std::max(0.0, margin)) * (1.0 - 1e-5);
    const float reach_sq = static_cast<float>(reach * reach);
    // The k + 1 nearest are those within the nearer of `reach` and a guess from the query before
    // (its (k+1)-th squared distance, 1.3 times): the guess keeps the selection short; when fewer
    // than k + 1 lie within it, the reach is taken.
    const std::size_t kk = static_cast<std::size_t>(k_) + 1;
    const std::size_t m = cx_.size();
    all_.resize(m);
    near_.resize(m);
    for (std::size_t j = 0; j < m; ++j) all_[j] = flann_squared_distance(q, cx_[j], cy_[j], cz_[j]);
    std::size_t count = 0;
    if (guess_sq_ > 0.0f && guess_sq_ < reach_sq) count = within(guess_sq_);
    if (count < kk) count = within(reach_sq);
    if (count < kk) return false;
    keep_nearest(near_.data(), count, kk);
    kth_sq_ = near_[kk - 1];
    guess_sq_ = kth_sq_ * 1.3f;
    mean = mean_of_nearest(near_.data(), k_);
    return true;
  }

  // The (k+1)-th nearest squared distance of the last query settled.
  float kth_sq() const { return kth_sq_; }

  // Sorts the kk smallest of a[0, count) to its front, nearest first (an insertion sort that
  // passes over what is not nearer than the kk-th so far: count is ~1.3 kk).
  static void keep_nearest(float* a, std::size_t count, std::size_t kk) {
    std::size_t have = 0;
    for (std::size_t j = 0; j < count; ++j) {
      const float v = a[j];
      if (have == kk && v >= a[kk - 1]) continue;
      std::size_t i = have < kk ? have++ : kk - 1;  // i <= j: a[j] is read before it is written
      for (; i > 0 && a[i - 1] > v; --i) a[i] = a[i - 1];
      a[i] = v;
    }
  }

  // Copies the squared distances up to `limit` to the front of near_; returns how many.
  std::size_t within(float limit) {
    std::size_t count = 0;
    for (std::size_t j = 0; j < all_.size(); ++j) {
      near_[count] = all_[j];
      count += all_[j] <= limit;
    }
    return count;
  }

 private:
  const Grid& g_;
  const int k_;
  std::vector<float> cx_, cy_, cz_, all_, near_;
  float guess_sq_ = 0.0f;
  float kth_sq_ = 0.0f;
};

// The grid's cell: 1.25 times the median distance of a point's (k+1)-th nearest, so that most
// queries settle in their cell's neighbours. A first grid has cells of about (k + 1) / 2 points
// where the cloud is a surface (n points over its largest face); the (k+1)-th nearest of 64 points
// spread over the cloud, found on it, give the cell of the grid used when it is more than 20 % off
// the first.
Grid grid_for(const PointCloud& cloud, int k) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d p = cloud.points[i].cast<double>();
    require(p.allFinite(), "mean_neighbour_distances",
            "point " + std::to_string(i) + " is not finite");
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double n = static_cast<double>(cloud.size());
  const double extent = std::max((hi - lo).maxCoeff(), 1e-9);
  const double finest = extent / static_cast<double>(kAxisCells - 4);
  const double first = std::max(finest, extent * std::sqrt(0.5 * (k + 1) / n));
  Grid g = build_grid(cloud, first, lo);
  RingSearch search(g, k);
  std::vector<double> kth;
  for (std::size_t s = 0; s < 64; ++s) {
    const std::size_t p = s * cloud.size() / 64;
    const float* q = &g.xyz[3 * p];
    const std::int64_t cell[3] = {g.axis_cell(q[0], 0), g.axis_cell(q[1], 1), g.axis_cell(q[2], 2)};
    double mean = 0.0;
    for (int ring = 1; ring <= kWidestRing; ++ring) {
      search.gather(cell[0], cell[1], cell[2], ring);
      if (search.settle(q, cell, ring, mean)) {
        kth.push_back(std::sqrt(static_cast<double>(search.kth_sq())));
        break;
      }
    }
  }
  if (kth.size() < 16) return g;
  std::nth_element(kth.begin(), kth.begin() + kth.size() / 2, kth.end());
  if (kth[kth.size() / 2] <= 0.0) return g;  // mostly repeated points: the first grid is as good
  const double cell = std::max(finest, 1.25 * kth[kth.size() / 2]);
  if (cell > 1.2 * first || cell < first / 1.2) g = build_grid(cloud, cell, lo);
  return g;
}

}  // namespace

std::vector<double> mean_neighbour_distances_kdtree(const PointCloud& cloud, int k, int threads) {
  std::vector<double> out(cloud.size());
  std::vector<std::uint32_t> all(cloud.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<std::uint32_t>(i);
  if (cloud.size() > static_cast<std::size_t>(k)) kdtree_distances(cloud, all, k, threads, out);
  return out;
}

std::vector<double> mean_neighbour_distances(const PointCloud& cloud, int k, int threads,
                                             NeighbourSearchStats* stats) {
  require(k >= 1, "mean_neighbour_distances", "k must be >= 1, got " + std::to_string(k));
  const std::size_t n = cloud.size();
  std::vector<double> out(n);
  if (n <= static_cast<std::size_t>(k)) return out;
  require(n < (std::size_t{1} << 32), "mean_neighbour_distances",
          "more than 2^32 - 1 points: " + std::to_string(n));
  const Grid g = grid_for(cloud, k);

  // Cells in chunks of about 1024 points (a record of a few thousand still splits), each chunk on
  // one thread with its own scratch. Every query writes only its own d_i, so the result does not
  // depend on the threads.
  std::vector<std::size_t> chunk_begin{0};
  for (std::size_t c = 0; c < g.keys.size(); ++c)
    if (g.begin[c + 1] - g.begin[chunk_begin.back()] >= 1024) chunk_begin.push_back(c + 1);
  if (chunk_begin.back() != g.keys.size()) chunk_begin.push_back(g.keys.size());
  std::vector<std::vector<std::uint32_t>> unsettled(chunk_begin.size() - 1);
  std::vector<std::size_t> wider(chunk_begin.size() - 1, 0);
  parallel_for(chunk_begin.size() - 1, threads, [&](std::size_t chunk) {
    RingSearch first(g, k), wide(g, k);
    for (std::size_t c = chunk_begin[chunk]; c < chunk_begin[chunk + 1]; ++c) {
      const Eigen::Vector3i centred = geometry::unpack_voxel(g.keys[c]);
      const std::int64_t cell[3] = {centred.x() + std::int64_t{geometry::kVoxelCoordLimit},
                                    centred.y() + std::int64_t{geometry::kVoxelCoordLimit},
                                    centred.z() + std::int64_t{geometry::kVoxelCoordLimit}};
      first.gather(cell[0], cell[1], cell[2], 1);
      int wide_ring = 0;  // the ring `wide` holds for this cell (gathered once per cell and ring)
      for (std::size_t p = g.begin[c]; p < g.begin[c + 1]; ++p) {
        const float* q = &g.xyz[3 * p];
        double& d = out[g.index[p]];
        if (first.settle(q, cell, 1, d)) continue;
        bool settled = false;
        for (int ring = 2; ring <= kWidestRing && !settled; ++ring) {
          if (wide_ring < ring) wide.gather(cell[0], cell[1], cell[2], wide_ring = ring);
          settled = wide.settle(q, cell, ring, d);
        }
        if (settled)
          ++wider[chunk];
        else
          unsettled[chunk].push_back(g.index[p]);
      }
    }
  });
  std::vector<std::uint32_t> rest;
  std::size_t wider_total = 0;
  for (std::size_t c = 0; c < unsettled.size(); ++c) {
    rest.insert(rest.end(), unsettled[c].begin(), unsettled[c].end());
    wider_total += wider[c];
  }
  std::sort(rest.begin(), rest.end());
  kdtree_distances(cloud, rest, k, threads, out);
  if (stats) {
    stats->cell_m = g.cell;
    stats->cells = g.keys.size();
    stats->by_kdtree = rest.size();
    stats->in_wider_rings = wider_total;
    stats->in_first_ring = n - rest.size() - wider_total;
  }
  return out;
}

}  // namespace objmap::filters
