#include "urban_detection/core/tracking/hungarian.h"

#include <algorithm>
#include <limits>

namespace urban_detection {
namespace core {

namespace {

// The potentials algorithm for n <= m over a callable cost a(i, j), 0-based. Each row is added
// in turn and an augmenting path of least reduced cost is grown from it (Dijkstra on reduced
// costs, which the potentials keep non-negative), so every step keeps the partial assignment
// optimal for the rows added so far.
template <class CostFn>
double solveRowsNotMoreThanCols(int n, int m, CostFn a, std::vector<int>* row_to_col,
                                std::vector<double>* work) {
  const double inf = std::numeric_limits<double>::infinity();
  // Working arrays, 1-based with index 0 as the virtual column/row of the path's start.
  work->assign(static_cast<std::size_t>(n + 1) + 3 * static_cast<std::size_t>(m + 1), 0.0);
  double* u = work->data();            // row potentials, n + 1
  double* v = u + (n + 1);             // column potentials, m + 1
  double* minv = v + (m + 1);          // least reduced cost to each column, m + 1
  double* slack_way = minv + (m + 1);  // previous column on the path (as double), m + 1
  std::vector<int> p(static_cast<std::size_t>(m + 1), 0);  // row assigned to column j (0 none)
  std::vector<char> used(static_cast<std::size_t>(m + 1), 0);
  for (int i = 1; i <= n; ++i) {
    p[0] = i;
    int j0 = 0;
    std::fill(minv, minv + m + 1, inf);
    std::fill(used.begin(), used.end(), 0);
    do {
      used[j0] = 1;
      const int i0 = p[j0];
      double delta = inf;
      int j1 = 0;
      for (int j = 1; j <= m; ++j) {
        if (used[j]) continue;
        const double reduced = a(i0 - 1, j - 1) - u[i0] - v[j];
        if (reduced < minv[j]) {
          minv[j] = reduced;
          slack_way[j] = j0;
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
    do {  // flip the path back to its start
      const int j1 = static_cast<int>(slack_way[j0]);
      p[j0] = p[j1];
      j0 = j1;
    } while (j0 != 0);
  }
  row_to_col->assign(static_cast<std::size_t>(n), -1);
  double total = 0.0;
  for (int j = 1; j <= m; ++j) {
    if (p[j] == 0) continue;
    (*row_to_col)[p[j] - 1] = j - 1;
    total += a(p[j] - 1, j - 1);
  }
  return total;
}

}  // namespace

double solveAssignment(const std::vector<double>& cost, int rows, int cols,
                       std::vector<int>* row_to_col, std::vector<double>* scratch) {
  std::vector<double> local;
  std::vector<double>* work = scratch ? scratch : &local;
  row_to_col->assign(static_cast<std::size_t>(std::max(rows, 0)), -1);
  if (rows <= 0 || cols <= 0 || cost.size() < static_cast<std::size_t>(rows) * cols) return 0.0;
  if (rows <= cols) {
    return solveRowsNotMoreThanCols(
        rows, cols, [&](int i, int j) { return cost[static_cast<std::size_t>(i) * cols + j]; },
        row_to_col, work);
  }
  // More rows than columns: solve the transpose, then invert the assignment.
  std::vector<int> col_to_row;
  const double total = solveRowsNotMoreThanCols(
      cols, rows, [&](int i, int j) { return cost[static_cast<std::size_t>(j) * cols + i]; },
      &col_to_row, work);
  for (int c = 0; c < cols; ++c) {
    if (col_to_row[c] >= 0) (*row_to_col)[col_to_row[c]] = c;
  }
  return total;
}

}  // namespace core
}  // namespace urban_detection
