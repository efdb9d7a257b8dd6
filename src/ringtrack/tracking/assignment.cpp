#include "ringtrack/tracking/assignment.hpp"

#include <cmath>
#include <limits>
#include <numeric>

namespace ringtrack::tracking {
namespace {

// Hungarian method for n <= m rows/columns: adds one row at a time and finds the cheapest
// augmenting path with Dijkstra on reduced costs (row potentials u, column potentials v), so
// every step keeps the partial assignment optimal. Index 0 is a virtual column that holds the
// row being inserted. Returns the column of each row.
std::vector<int> hungarian_rows_le_cols(const Eigen::MatrixXd& a) {
  const int n = static_cast<int>(a.rows());
  const int m = static_cast<int>(a.cols());
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> u(n + 1, 0.0), v(m + 1, 0.0), min_reduced(m + 1);
  std::vector<int> row_of_col(m + 1, 0), previous_col(m + 1, 0);
  std::vector<char> visited(m + 1);
  for (int row = 1; row <= n; ++row) {
    row_of_col[0] = row;
    int col = 0;
    std::fill(min_reduced.begin(), min_reduced.end(), kInf);
    std::fill(visited.begin(), visited.end(), 0);
    do {
      visited[col] = 1;
      const int r = row_of_col[col];
      double delta = kInf;
      int next = 0;
      for (int j = 1; j <= m; ++j) {
        if (visited[j]) continue;
        const double reduced = a(r - 1, j - 1) - u[r] - v[j];
        if (reduced < min_reduced[j]) {
          min_reduced[j] = reduced;
          previous_col[j] = col;
        }
        if (min_reduced[j] < delta) {
          delta = min_reduced[j];
          next = j;
        }
      }
      for (int j = 0; j <= m; ++j) {
        if (visited[j]) {
          u[row_of_col[j]] += delta;
          v[j] -= delta;
        } else {
          min_reduced[j] -= delta;
        }
      }
      col = next;
    } while (row_of_col[col] != 0);
    // Flip the augmenting path back to the virtual column.
    do {
      const int prev = previous_col[col];
      row_of_col[col] = row_of_col[prev];
      col = prev;
    } while (col != 0);
  }
  std::vector<int> col_of_row(n, kUnassigned);
  for (int j = 1; j <= m; ++j) {
    if (row_of_col[j] != 0) col_of_row[row_of_col[j] - 1] = j - 1;
  }
  return col_of_row;
}

int find_root(std::vector<int>& parent, int i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

}  // namespace

std::vector<int> solve_assignment(const Eigen::MatrixXd& cost) {
  if (cost.rows() == 0) return {};
  if (cost.cols() == 0) return std::vector<int>(cost.rows(), kUnassigned);
  if (cost.rows() <= cost.cols()) return hungarian_rows_le_cols(cost);
  const std::vector<int> row_of_col = hungarian_rows_le_cols(cost.transpose());
  std::vector<int> col_of_row(cost.rows(), kUnassigned);
  for (std::size_t j = 0; j < row_of_col.size(); ++j)
    col_of_row[row_of_col[j]] = static_cast<int>(j);
  return col_of_row;
}

namespace {

// One connected component of allowed pairs as a square problem: real pairs top-left, "row
// unpaired" dummies top-right (diagonal at the gate), "column unpaired" dummies bottom-left,
// dummy-dummy pairs free. Forbidden entries cost more than leaving everything unpaired, so no
// optimum uses them. Writes the component's pairs into col_of_row.
void solve_component(const Eigen::MatrixXd& cost, double gate, const std::vector<int>& comp_rows,
                     const std::vector<int>& comp_cols, std::vector<int>& col_of_row) {
  const int nr = static_cast<int>(comp_rows.size());
  const int nc = static_cast<int>(comp_cols.size());
  const int n = nr + nc;
  const double forbidden = 2.0 * gate * n + 1.0;
  Eigen::MatrixXd square = Eigen::MatrixXd::Constant(n, n, forbidden);
  for (int a = 0; a < nr; ++a) {
    for (int b = 0; b < nc; ++b) {
      const double c = cost(comp_rows[a], comp_cols[b]);
      if (std::isfinite(c) && c <= gate) square(a, b) = c;
    }
    square(a, nc + a) = gate;
  }
  for (int b = 0; b < nc; ++b) square(nr + b, b) = gate;
  square.bottomRightCorner(nc, nr).setZero();
  const std::vector<int> solution = hungarian_rows_le_cols(square);
  for (int a = 0; a < nr; ++a) {
    if (solution[a] < nc) col_of_row[comp_rows[a]] = comp_cols[solution[a]];
  }
}

}  // namespace

std::vector<int> solve_gated_assignment(const Eigen::MatrixXd& cost, double gate) {
  const int rows = static_cast<int>(cost.rows());
  const int cols = static_cast<int>(cost.cols());
  std::vector<int> col_of_row(rows, kUnassigned);
  const auto allowed = [&](int i, int j) {
    const double c = cost(i, j);
    return std::isfinite(c) && c <= gate;
  };
  // Components of the bipartite graph of allowed pairs: rows 0..rows-1, columns after them.
  std::vector<int> parent(rows + cols);
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<int> degree(rows + cols, 0);
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < cols; ++j) {
      if (!allowed(i, j)) continue;
      ++degree[i];
      ++degree[rows + j];
      const int a = find_root(parent, i), b = find_root(parent, rows + j);
      if (a != b) parent[a] = b;
    }
  }
  // Isolated pairs (the common case of separated targets) need no matrix; nodes without an
  // allowed pair stay unpaired.
  std::vector<char> done(rows + cols, 0);
  for (int i = 0; i < rows; ++i) {
    if (degree[i] != 1) continue;
    for (int j = 0; j < cols; ++j) {
      if (allowed(i, j) && degree[rows + j] == 1) {
        col_of_row[i] = j;
        done[i] = done[rows + j] = 1;
      }
    }
  }
  // Group the remaining nodes by component (counting sort on the root).
  std::vector<int> root(rows + cols);
  std::vector<int> members_start(rows + cols + 1, 0);
  for (int k = 0; k < rows + cols; ++k) {
    root[k] = find_root(parent, k);
    if (degree[k] > 0 && !done[k]) ++members_start[root[k] + 1];
  }
  std::partial_sum(members_start.begin(), members_start.end(), members_start.begin());
  std::vector<int> members(static_cast<std::size_t>(members_start.back()));
  std::vector<int> fill = members_start;
  for (int k = 0; k < rows + cols; ++k) {
    if (degree[k] > 0 && !done[k]) members[fill[root[k]]++] = k;
  }
  std::vector<int> comp_rows, comp_cols;
  for (int r = 0; r < rows + cols; ++r) {
    if (members_start[r + 1] == members_start[r]) continue;
    comp_rows.clear();
    comp_cols.clear();
    for (int k = members_start[r]; k < members_start[r + 1]; ++k) {
      if (members[k] < rows) {
        comp_rows.push_back(members[k]);
      } else {
        comp_cols.push_back(members[k] - rows);
      }
    }
    solve_component(cost, gate, comp_rows, comp_cols, col_of_row);
  }
  return col_of_row;
}

}  // namespace ringtrack::tracking
