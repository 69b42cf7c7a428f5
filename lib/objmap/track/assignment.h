#pragma once
#include <algorithm>
#include <limits>
#include <vector>

#include <Eigen/Core>

// Minimum-cost assignment (the Hungarian method, O(n^3) with potentials and shortest augmenting
// paths, as in Jonker-Volgenant / scipy's linear_sum_assignment). Header-only so that the tracker
// and the track evaluation (objmap_eval) share it without a link dependency.
namespace objmap::track {

// For a rows x cols matrix of finite costs: the column assigned to each row (-1 when the row is
// unassigned, which happens only when rows > cols), such that min(rows, cols) pairs are made and
// their total cost is minimal. Ties are broken deterministically.
inline std::vector<int> solve_assignment(const Eigen::MatrixXd& cost) {
  const int rows = static_cast<int>(cost.rows()), cols = static_cast<int>(cost.cols());
  std::vector<int> row_to_col(rows, -1);
  if (rows == 0 || cols == 0) return row_to_col;
  // The method below needs n <= m: solve the transpose when there are more rows than columns.
  const bool transposed = rows > cols;
  const int n = transposed ? cols : rows, m = transposed ? rows : cols;
  const auto a = [&](int i, int j) { return transposed ? cost(j, i) : cost(i, j); };  // 0-based
  const double inf = std::numeric_limits<double>::infinity();
  // 1-based potentials u (rows), v (columns); p[j] = row matched to column j (0 = none).
  std::vector<double> u(n + 1, 0.0), v(m + 1, 0.0);
  std::vector<int> p(m + 1, 0), way(m + 1, 0);
  for (int i = 1; i <= n; ++i) {
    p[0] = i;
    int j0 = 0;
    std::vector<double> minv(m + 1, inf);
    std::vector<char> used(m + 1, 0);
    do {  // Dijkstra-like growth of the alternating tree until a free column is reached
      used[j0] = 1;
      const int i0 = p[j0];
      double delta = inf;
      int j1 = 0;
      for (int j = 1; j <= m; ++j) {
        if (used[j]) continue;
        const double reduced = a(i0 - 1, j - 1) - u[i0] - v[j];
        if (reduced < minv[j]) {
          minv[j] = reduced;
          way[j] = j0;
        }
        if (minv[j] < delta) {
          delta = minv[j];
          j1 = j;
        }
      }
      for (int j = 0; j <= m; ++j) {
        if (used[j]) {
          u[p[j]] += delta;
          v[j] -= delta;
        } else {
          minv[j] -= delta;
        }
      }
      j0 = j1;
    } while (p[j0] != 0);
    do {  // augment along the path
      const int j1 = way[j0];
      p[j0] = p[j1];
      j0 = j1;
    } while (j0 != 0);
  }
  for (int j = 1; j <= m; ++j) {
    if (p[j] == 0) continue;
    if (transposed)
      row_to_col[j - 1] = p[j] - 1;
    else
      row_to_col[p[j] - 1] = j - 1;
  }
  return row_to_col;
}

}  // namespace objmap::track
