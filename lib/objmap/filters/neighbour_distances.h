#pragma once
#include <cstddef>
#include <vector>

#include "objmap/core/types.h"

namespace objmap::filters {

// What the grid search did (for the benchmark and the tests).
struct NeighbourSearchStats {
  double cell_m = 0.0;             // the grid's cell
  std::size_t cells = 0;           // occupied cells
  std::size_t in_first_ring = 0;   // queries settled by their cell and its 26 neighbours
  std::size_t in_wider_rings = 0;  // settled by the cells up to 4 cells away
  std::size_t by_kdtree = 0;       // left to FLANN's kd-tree (points far from the rest)
};

// d_i of eq 18 for every point: the mean distance to its k nearest neighbours, the point itself
// excluded (as the first of k + 1 hits). The k + 1 nearest come from a grid of the points (cells
// of about the (k+1)-th nearest's distance): the cells around a query hold its neighbours when
// the (k+1)-th nearest is nearer than any cell not searched can be; the queries that this does
// not settle (points far from the rest) go to FLANN's exact kd-tree. Distances are computed as
// FLANN's L2_Simple<float> computes them and summed nearest first, so the result is bit for bit
// that of the kd-tree alone (`mean_neighbour_distances_kdtree`), for any `threads`. Points must
// be finite (InputError).
std::vector<double> mean_neighbour_distances(const PointCloud& cloud, int k, int threads,
                                             NeighbourSearchStats* stats = nullptr);

// The same from FLANN's single kd-tree alone (leaves of 15, exact search): the reference.
std::vector<double> mean_neighbour_distances_kdtree(const PointCloud& cloud, int k, int threads);

}  // namespace objmap::filters
