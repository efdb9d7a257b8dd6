// The Hungarian method and its gated variant against brute-force enumeration.

#include "ringtrack/tracking/assignment.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

namespace ringtrack::tracking {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double total(const Eigen::MatrixXd& c, const std::vector<int>& col_of_row) {
  double sum = 0;
  for (std::size_t i = 0; i < col_of_row.size(); ++i) {
    if (col_of_row[i] != kUnassigned) sum += c(static_cast<Eigen::Index>(i), col_of_row[i]);
  }
  return sum;
}

// Checks that the assignment is one-to-one and pairs min(rows, cols) rows.
void expect_valid_full(const Eigen::MatrixXd& c, const std::vector<int>& col_of_row) {
  ASSERT_EQ(col_of_row.size(), static_cast<std::size_t>(c.rows()));
  std::vector<int> used(c.cols(), 0);
  int paired = 0;
  for (int col : col_of_row) {
    if (col == kUnassigned) continue;
    ASSERT_GE(col, 0);
    ASSERT_LT(col, c.cols());
    EXPECT_EQ(used[col]++, 0) << "column used twice";
    ++paired;
  }
  EXPECT_EQ(paired, std::min(c.rows(), c.cols()));
}

// Minimum over every injective map of the smaller side into the larger.
double brute_force_full(const Eigen::MatrixXd& c) {
  const bool transpose = c.rows() > c.cols();
  const Eigen::MatrixXd a = transpose ? Eigen::MatrixXd(c.transpose()) : c;
  std::vector<int> cols(a.cols());
  std::iota(cols.begin(), cols.end(), 0);
  double best = kInf;
  // Every permutation of the columns; the first rows() of them form an injective map.
  do {
    double sum = 0;
    for (Eigen::Index i = 0; i < a.rows(); ++i) sum += a(i, cols[i]);
    best = std::min(best, sum);
  } while (std::next_permutation(cols.begin(), cols.end()));
  return best;
}

// Minimum over every partial matching of allowed pairs, unpaired rows/columns costing gate.
double brute_force_gated(const Eigen::MatrixXd& c, double gate, int row, std::vector<char>& used) {
  if (row == c.rows()) {
    double unpaired_cols = 0;
    for (char u : used) unpaired_cols += u ? 0 : gate;
    return unpaired_cols;
  }
  double best = gate + brute_force_gated(c, gate, row + 1, used);
  for (Eigen::Index j = 0; j < c.cols(); ++j) {
    if (used[j] || !std::isfinite(c(row, j)) || c(row, j) > gate) continue;
    used[j] = 1;
    best = std::min(best, c(row, j) + brute_force_gated(c, gate, row + 1, used));
    used[j] = 0;
  }
  return best;
}

TEST(Hungarian, MatchesBruteForceOnRandomMatrices) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> value(0.0, 10.0);
  std::uniform_int_distribution<int> size(1, 7);
  for (int trial = 0; trial < 400; ++trial) {
    const int rows = size(rng), cols = size(rng);
    Eigen::MatrixXd c(rows, cols);
    for (int i = 0; i < rows; ++i) {
      for (int j = 0; j < cols; ++j) {
        // Integer costs in some trials force many ties.
        c(i, j) = trial % 2 == 0 ? value(rng) : std::floor(value(rng) / 3.0);
      }
    }
    const auto solution = solve_assignment(c);
    expect_valid_full(c, solution);
    EXPECT_NEAR(total(c, solution), brute_force_full(c), 1e-9) << c;
  }
}

TEST(Hungarian, HandPickedCase) {
  // The greedy choice (0,0)=1 forces (1,1)=100; the optimum is the anti-diagonal, 2 + 3.
  Eigen::MatrixXd c(2, 2);
  c << 1, 2, 3, 100;
  EXPECT_EQ(solve_assignment(c), (std::vector<int>{1, 0}));
  EXPECT_TRUE(solve_assignment(Eigen::MatrixXd(0, 3)).empty());
  EXPECT_EQ(solve_assignment(Eigen::MatrixXd(2, 0)), (std::vector<int>{kUnassigned, kUnassigned}));
}

TEST(GatedAssignment, MatchesBruteForceOnRandomMatrices) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> value(0.0, 10.0);
  std::uniform_int_distribution<int> size(0, 6);
  std::uniform_int_distribution<int> percent(0, 99);
  for (int trial = 0; trial < 600; ++trial) {
    const int rows = size(rng), cols = size(rng);
    const double gate = 1.0 + value(rng) * 0.5;
    Eigen::MatrixXd c(rows, cols);
    for (int i = 0; i < rows; ++i) {
      for (int j = 0; j < cols; ++j) c(i, j) = percent(rng) < 20 ? kInf : value(rng);
    }
    const auto solution = solve_gated_assignment(c, gate);
    ASSERT_EQ(solution.size(), static_cast<std::size_t>(rows));
    std::vector<char> used(cols, 0);
    int paired = 0;
    for (int i = 0; i < rows; ++i) {
      const int j = solution[i];
      if (j == kUnassigned) continue;
      ASSERT_TRUE(j >= 0 && j < cols);
      EXPECT_EQ(used[j], 0);
      used[j] = 1;
      EXPECT_LE(c(i, j), gate) << "forbidden pair used";
      ++paired;
    }
    const double cost = total(c, solution) + gate * (rows - paired) + gate * (cols - paired);
    std::vector<char> scratch(cols, 0);
    EXPECT_NEAR(cost, brute_force_gated(c, gate, 0, scratch), 1e-9) << "gate " << gate << "\n" << c;
  }
}

TEST(GatedAssignment, SeparatedBlocksAndConflicts) {
  // Rows 0 and 1 both want column 0; row 1 has an alternative, row 0 does not.
  Eigen::MatrixXd c(3, 3);
  c << 0.5, kInf, kInf,  //
      0.4, 0.9, kInf,    //
      kInf, kInf, 0.2;
  EXPECT_EQ(solve_gated_assignment(c, 1.0), (std::vector<int>{0, 1, 2}));
  // Everything above the gate: nothing pairs.
  EXPECT_EQ(solve_gated_assignment(c, 0.1),
            (std::vector<int>{kUnassigned, kUnassigned, kUnassigned}));
}

}  // namespace
}  // namespace ringtrack::tracking
