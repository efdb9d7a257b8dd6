#include "ringtrack/eval/assignment.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace ringtrack::eval {
namespace {

// Shortest-augmenting-path Hungarian method with row/column potentials for n <= m.
// Columns and rows are 1-based inside; column 0 is the virtual start of each augmenting path.
std::vector<Eigen::Index> solve_wide(const Eigen::MatrixXd& cost) {
  const Eigen::Index n = cost.rows();
  const Eigen::Index m = cost.cols();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> row_potential(static_cast<std::size_t>(n + 1), 0.0);
  std::vector<double> col_potential(static_cast<std::size_t>(m + 1), 0.0);
  std::vector<Eigen::Index> col_owner(static_cast<std::size_t>(m + 1), 0);  // 1-based row, 0 = free
  std::vector<Eigen::Index> came_from(static_cast<std::size_t>(m + 1), 0);
  std::vector<double> slack(static_cast<std::size_t>(m + 1));
  std::vector<char> visited(static_cast<std::size_t>(m + 1));
  const auto at = [](auto& v, Eigen::Index i) -> auto& {
    return v[static_cast<std::size_t>(i)];
  };

  for (Eigen::Index row = 1; row <= n; ++row) {
    at(col_owner, 0) = row;
    Eigen::Index col = 0;
    std::fill(slack.begin(), slack.end(), kInf);
    std::fill(visited.begin(), visited.end(), 0);
    // Grow a tree of tight edges (Dijkstra on reduced costs) until a free column is reached.
    do {
      at(visited, col) = 1;
      const Eigen::Index owner = at(col_owner, col);
      double delta = kInf;
      Eigen::Index next = 0;
      for (Eigen::Index j = 1; j <= m; ++j) {
        if (at(visited, j) != 0) continue;
        const double reduced =
            cost(owner - 1, j - 1) - at(row_potential, owner) - at(col_potential, j);
        if (reduced < at(slack, j)) {
          at(slack, j) = reduced;
          at(came_from, j) = col;
        }
        if (at(slack, j) < delta) {
          delta = at(slack, j);
          next = j;
        }
      }
      for (Eigen::Index j = 0; j <= m; ++j) {
        if (at(visited, j) != 0) {
          at(row_potential, at(col_owner, j)) += delta;
          at(col_potential, j) -= delta;
        } else {
          at(slack, j) -= delta;
        }
      }
      col = next;
    } while (at(col_owner, col) != 0);
    // Flip the augmenting path back to the virtual column.
    while (col != 0) {
      const Eigen::Index prev = at(came_from, col);
      at(col_owner, col) = at(col_owner, prev);
      col = prev;
    }
  }
  std::vector<Eigen::Index> row_to_col(static_cast<std::size_t>(n), kUnassigned);
  for (Eigen::Index j = 1; j <= m; ++j) {
    if (at(col_owner, j) != 0) at(row_to_col, at(col_owner, j) - 1) = j - 1;
  }
  return row_to_col;
}

}  // namespace

std::vector<Eigen::Index> min_cost_assignment(const Eigen::MatrixXd& cost) {
  const Eigen::Index rows = cost.rows();
  const Eigen::Index cols = cost.cols();
  std::vector<Eigen::Index> row_to_col(static_cast<std::size_t>(rows), kUnassigned);
  if (rows == 0 || cols == 0) return row_to_col;
  if (!cost.allFinite()) {
    throw std::invalid_argument("min_cost_assignment: every cost must be finite");
  }
  if (rows <= cols) return solve_wide(cost);
  const Eigen::MatrixXd transposed = cost.transpose();
  const std::vector<Eigen::Index> col_to_row = solve_wide(transposed);
  for (std::size_t c = 0; c < col_to_row.size(); ++c) {
    if (col_to_row[c] != kUnassigned) {
      row_to_col[static_cast<std::size_t>(col_to_row[c])] = static_cast<Eigen::Index>(c);
    }
  }
  return row_to_col;
}

std::vector<Eigen::Index> max_matching_min_cost(const Eigen::MatrixXd& distance) {
  const Eigen::Index rows = distance.rows();
  const Eigen::Index cols = distance.cols();
  std::vector<Eigen::Index> row_to_col(static_cast<std::size_t>(rows), kUnassigned);
  // Only rows and columns with at least one pairable entry take part: smaller problem, same
  // optimum.
  std::vector<Eigen::Index> active_rows;
  std::vector<Eigen::Index> active_cols;
  std::vector<char> col_active(static_cast<std::size_t>(cols), 0);
  double largest = 0.0;
  for (Eigen::Index i = 0; i < rows; ++i) {
    bool any = false;
    for (Eigen::Index j = 0; j < cols; ++j) {
      const double d = distance(i, j);
      if (d < 0.0) {
        throw std::invalid_argument("max_matching_min_cost: negative distance at (" +
                                    std::to_string(i) + ", " + std::to_string(j) + ")");
      }
      if (std::isfinite(d)) {
        any = true;
        col_active[static_cast<std::size_t>(j)] = 1;
        largest = std::max(largest, d);
      }
    }
    if (any) active_rows.push_back(i);
  }
  for (Eigen::Index j = 0; j < cols; ++j) {
    if (col_active[static_cast<std::size_t>(j)] != 0) active_cols.push_back(j);
  }
  if (active_rows.empty()) return row_to_col;

  // A forbidden pair costs more than any complete set of allowed pairs, so the optimum first
  // maximises the number of allowed pairs and then minimises their total distance.
  const auto k = static_cast<double>(std::min(active_rows.size(), active_cols.size()));
  const double forbidden = (k + 1.0) * (largest + 1.0);
  Eigen::MatrixXd cost(static_cast<Eigen::Index>(active_rows.size()),
                       static_cast<Eigen::Index>(active_cols.size()));
  for (Eigen::Index a = 0; a < cost.rows(); ++a) {
    for (Eigen::Index b = 0; b < cost.cols(); ++b) {
      const double d = distance(active_rows[static_cast<std::size_t>(a)],
                                active_cols[static_cast<std::size_t>(b)]);
      cost(a, b) = std::isfinite(d) ? d : forbidden;
    }
  }
  const std::vector<Eigen::Index> sub = min_cost_assignment(cost);
  for (std::size_t a = 0; a < sub.size(); ++a) {
    if (sub[a] == kUnassigned) continue;
    const Eigen::Index i = active_rows[a];
    const Eigen::Index j = active_cols[static_cast<std::size_t>(sub[a])];
    if (std::isfinite(distance(i, j))) row_to_col[static_cast<std::size_t>(i)] = j;
  }
  return row_to_col;
}

}  // namespace ringtrack::eval
