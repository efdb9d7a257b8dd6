// Hungarian solver against exhaustive enumeration on random small matrices.

#include "ringtrack/eval/assignment.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace ringtrack::eval {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Best {
  int pairs = -1;
  double cost = kInf;
};

// Every partial injective assignment of rows to columns; with `all_rows_of_smaller_side` the
// cost of each complete one (min(n, m) pairs) over finite entries, else the lexicographic best
// (most pairable pairs, then least cost) where non-finite entries cannot be used.
void enumerate(const Eigen::MatrixXd& c, Eigen::Index row, std::vector<char>& used, int pairs,
               double cost, bool complete_only, Best& best) {
  if (row == c.rows()) {
    const int need = static_cast<int>(std::min(c.rows(), c.cols()));
    if (complete_only && pairs != need) return;
    if (pairs > best.pairs || (pairs == best.pairs && cost < best.cost)) best = {pairs, cost};
    return;
  }
  enumerate(c, row + 1, used, pairs, cost, complete_only, best);  // row left unassigned
  for (Eigen::Index j = 0; j < c.cols(); ++j) {
    if (used[static_cast<std::size_t>(j)] != 0 || !std::isfinite(c(row, j))) continue;
    used[static_cast<std::size_t>(j)] = 1;
    enumerate(c, row + 1, used, pairs + 1, cost + c(row, j), complete_only, best);
    used[static_cast<std::size_t>(j)] = 0;
  }
}

Best brute_force(const Eigen::MatrixXd& c, bool complete_only) {
  std::vector<char> used(static_cast<std::size_t>(c.cols()), 0);
  Best best;
  enumerate(c, 0, used, 0, 0.0, complete_only, best);
  return best;
}

// Checks the assignment is injective and uses finite entries; returns (pairs, cost).
Best evaluate(const Eigen::MatrixXd& c, const std::vector<Eigen::Index>& a) {
  EXPECT_EQ(a.size(), static_cast<std::size_t>(c.rows()));
  std::vector<char> used(static_cast<std::size_t>(c.cols()), 0);
  Best b{0, 0.0};
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i] == kUnassigned) continue;
    EXPECT_GE(a[i], 0);
    EXPECT_LT(a[i], c.cols());
    EXPECT_EQ(used[static_cast<std::size_t>(a[i])], 0) << "column used twice";
    used[static_cast<std::size_t>(a[i])] = 1;
    const double v = c(static_cast<Eigen::Index>(i), a[i]);
    EXPECT_TRUE(std::isfinite(v));
    ++b.pairs;
    b.cost += v;
  }
  return b;
}

TEST(Assignment, EmptyMatrices) {
  EXPECT_TRUE(min_cost_assignment(Eigen::MatrixXd(0, 3)).empty());
  EXPECT_EQ(min_cost_assignment(Eigen::MatrixXd(2, 0)),
            (std::vector<Eigen::Index>{kUnassigned, kUnassigned}));
  EXPECT_EQ(max_matching_min_cost(Eigen::MatrixXd(2, 0)).size(), 2u);
}

TEST(Assignment, HandExample) {
  Eigen::MatrixXd c(3, 3);
  c << 4, 1, 3,  //
      2, 0, 5,   //
      3, 2, 2;
  // Optimum 1 + 2 + 2 = 5: (0,1), (1,0), (2,2).
  EXPECT_EQ(min_cost_assignment(c), (std::vector<Eigen::Index>{1, 0, 2}));
}

TEST(Assignment, RejectsNonFiniteAndNegative) {
  Eigen::MatrixXd c(1, 2);
  c << 1.0, kInf;
  EXPECT_THROW((void)min_cost_assignment(c), std::invalid_argument);
  c << 1.0, -0.5;
  EXPECT_THROW((void)max_matching_min_cost(c), std::invalid_argument);
}

TEST(Assignment, PrefersMorePairsOverLowerCost) {
  // One pair (0,0) at 0.1 versus two pairs at 0.9 + 0.9: two pairs win.
  Eigen::MatrixXd c(2, 2);
  c << 0.1, 0.9,  //
      0.9, kInf;
  EXPECT_EQ(max_matching_min_cost(c), (std::vector<Eigen::Index>{1, 0}));
}

TEST(Assignment, MatchesBruteForceOnRandomFiniteMatrices) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> value(-5.0, 10.0);
  std::uniform_int_distribution<int> size(1, 6);
  for (int trial = 0; trial < 600; ++trial) {
    Eigen::MatrixXd c(size(rng), size(rng));
    for (Eigen::Index i = 0; i < c.size(); ++i) {
      // Small integers half the time: many ties.
      c(i) = trial % 2 == 0 ? std::round(value(rng) / 3.0) : value(rng);
    }
    const Best expected = brute_force(c, true);
    const Best got = evaluate(c, min_cost_assignment(c));
    ASSERT_EQ(got.pairs, expected.pairs) << c;
    ASSERT_NEAR(got.cost, expected.cost, 1e-9) << c;
  }
}

TEST(Assignment, MaxMatchingMatchesBruteForceWithForbiddenEntries) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> value(0.0, 3.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> size(1, 6);
  for (int trial = 0; trial < 800; ++trial) {
    Eigen::MatrixXd c(size(rng), size(rng));
    const double forbidden_share = unit(rng);
    for (Eigen::Index i = 0; i < c.size(); ++i) {
      const double u = unit(rng);
      if (u < forbidden_share) {
        c(i) = u < forbidden_share / 2 ? kInf : std::numeric_limits<double>::quiet_NaN();
      } else {
        c(i) = trial % 3 == 0 ? std::round(value(rng)) : value(rng);
      }
    }
    const Best expected = brute_force(c, false);
    const Best got = evaluate(c, max_matching_min_cost(c));
    ASSERT_EQ(got.pairs, expected.pairs) << c;
    ASSERT_NEAR(got.cost, expected.cost, 1e-9) << c;
  }
}

TEST(Assignment, LargerRandomProblemIsAPermutationWithOptimalityCertificate) {
  // For 40x40 enumeration is impossible; check the optimum against all 2-swaps instead.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> value(0.0, 1.0);
  Eigen::MatrixXd c(40, 40);
  for (Eigen::Index i = 0; i < c.size(); ++i) c(i) = value(rng);
  const std::vector<Eigen::Index> a = min_cost_assignment(c);
  const Best got = evaluate(c, a);
  ASSERT_EQ(got.pairs, 40);
  for (Eigen::Index i = 0; i < 40; ++i) {
    for (Eigen::Index k = i + 1; k < 40; ++k) {
      const double now =
          c(i, a[static_cast<std::size_t>(i)]) + c(k, a[static_cast<std::size_t>(k)]);
      const double swapped =
          c(i, a[static_cast<std::size_t>(k)]) + c(k, a[static_cast<std::size_t>(i)]);
      ASSERT_LE(now, swapped + 1e-12);
    }
  }
}

}  // namespace
}  // namespace ringtrack::eval
