#pragma once
/// Optimal linear assignment (Hungarian method, O(n^2 m)) for the evaluation metrics.

#include <Eigen/Core>
#include <vector>

namespace ringtrack::eval {

/// Marks a row without a column in an assignment.
inline constexpr Eigen::Index kUnassigned = -1;

/// Minimum-total-cost assignment on a rectangular matrix of finite costs: every row of the
/// smaller side gets a distinct column. Returns, per row, its column or kUnassigned.
/// Ties between equal-cost assignments are resolved deterministically by row/column order.
/// Throws std::invalid_argument on a non-finite entry.
[[nodiscard]] std::vector<Eigen::Index> min_cost_assignment(const Eigen::MatrixXd& cost);

/// Matching on a matrix of non-negative distances where NaN or infinity means "not pairable":
/// first the largest number of pairs, then, among those, the smallest total distance.
/// Returns, per row, its column or kUnassigned. Throws std::invalid_argument on a negative entry.
[[nodiscard]] std::vector<Eigen::Index> max_matching_min_cost(const Eigen::MatrixXd& distance);

}  // namespace ringtrack::eval
