#pragma once
/// Optimal assignment: the Hungarian method (shortest augmenting paths with potentials, O(n^3))
/// and the gated variant the tracker uses.

#include <Eigen/Core>
#include <vector>

namespace ringtrack::tracking {

/// Marks a row or column without a partner.
inline constexpr int kUnassigned = -1;

/// Minimum-cost assignment on a rectangular matrix of finite costs: every row is paired with a
/// distinct column when rows <= cols, every column with a distinct row otherwise. Returns the
/// column of each row (kUnassigned for rows left over when rows > cols).
std::vector<int> solve_assignment(const Eigen::MatrixXd& cost);

/// Gated assignment on non-negative costs (distances): row i may pair with column j only when
/// cost(i, j) <= gate (non-finite entries are forbidden); every row or column left unpaired
/// costs gate. Minimises the total, so an allowed pair always beats leaving both unpaired.
/// Solves each connected component of the allowed pairs separately, which keeps
/// well-separated targets linear in their number. Returns the column of each row or
/// kUnassigned.
std::vector<int> solve_gated_assignment(const Eigen::MatrixXd& cost, double gate);

}  // namespace ringtrack::tracking
