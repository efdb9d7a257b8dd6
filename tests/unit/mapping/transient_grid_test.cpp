// The transient line's grid against a naive reference: every noted point kept in a list, and a
// point confirmed when a listed point at least k scans away lies in its cell or one of the eight
// around it (cells by std::floor, as the definition says).

#include "ringtrack/mapping/transient_grid.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "ringtrack/core/error.hpp"

namespace ringtrack::mapping {
namespace {

struct Noted {
  Eigen::Vector3f p;
  std::uint64_t sequence;
};

bool naive_confirmed(const std::vector<Noted>& noted, const Eigen::Vector3f& p,
                     std::uint64_t sequence, std::uint64_t k, double cell_m) {
  const auto cell = [&](float v) { return std::floor(static_cast<double>(v) / cell_m); };
  for (const auto& n : noted) {
    const bool near = std::abs(cell(n.p.x()) - cell(p.x())) <= 1.0 &&
                      std::abs(cell(n.p.y()) - cell(p.y())) <= 1.0;
    const bool apart = n.sequence + k <= sequence || n.sequence >= sequence + k;
    if (near && apart) return true;
  }
  return false;
}

TEST(TransientGrid, MatchesANaiveListOfEveryNotedPoint) {
  constexpr double kCell = 0.15;
  constexpr std::uint64_t kNever = std::numeric_limits<std::uint64_t>::max() / 4;
  std::mt19937 rng(7);
  // A small area, so that cells are shared and neighbours matter; negative coordinates too.
  std::uniform_real_distribution<float> coordinate(-6.0f, 6.0f);
  std::uniform_int_distribution<int> count(0, 20);
  TransientGrid one_by_one(kCell, kNever);
  TransientGrid batched(kCell, kNever);
  std::vector<Noted> noted;
  for (std::uint64_t s = 0; s < 120; ++s) {
    std::vector<std::uint64_t> keys;
    const int n = count(rng);
    for (int j = 0; j < n; ++j) {
      const Eigen::Vector3f p(coordinate(rng), coordinate(rng), coordinate(rng));
      one_by_one.note(p, s);
      keys.push_back(batched.key(p));
      noted.push_back({p, s});
    }
    batched.note(keys, s);
  }
  int confirmations = 0;
  for (int q = 0; q < 3000; ++q) {
    const Eigen::Vector3f p(coordinate(rng), coordinate(rng), 0.0f);
    const std::uint64_t s = static_cast<std::uint64_t>(q % 130);
    const std::uint64_t k = static_cast<std::uint64_t>(1 + q % 40);
    const bool expected = naive_confirmed(noted, p, s, k, kCell);
    confirmations += expected ? 1 : 0;
    ASSERT_EQ(one_by_one.confirmed(p, s, k), expected) << "query " << q;
    ASSERT_EQ(batched.confirmed(p, s, k), expected) << "query " << q;
    std::vector<std::uint32_t> out;
    batched.unconfirmed({batched.key(p)}, s, k, out);
    ASSERT_EQ(out.empty(), expected) << "query " << q;
  }
  EXPECT_EQ(one_by_one.size(), batched.size());
  // Both answers are exercised.
  EXPECT_GT(confirmations, 300);
  EXPECT_LT(confirmations, 2700);
}

TEST(TransientGrid, AWalkerIsNotConfirmedWhatStandsIs) {
  TransientGrid grid(0.15, 600);
  for (std::uint64_t s = 0; s < 100; ++s) {
    grid.note(Eigen::Vector3f(0.14f * static_cast<float>(s), 5.0f, 1.0f), s);  // 1.4 m/s
    grid.note(Eigen::Vector3f(-3.0f, -5.0f, 1.0f), s);                         // a post
  }
  for (std::uint64_t s = 20; s < 80; ++s) {
    EXPECT_FALSE(grid.confirmed(Eigen::Vector3f(0.14f * static_cast<float>(s), 5.0f, 1.0f), s, 20))
        << "scan " << s;
    EXPECT_TRUE(grid.confirmed(Eigen::Vector3f(-3.0f, -5.0f, 1.0f), s, 20)) << "scan " << s;
  }
  // Height does not matter (a post's points on every ring confirm each other).
  EXPECT_TRUE(grid.confirmed(Eigen::Vector3f(-3.0f, -5.0f, 9.0f), 50, 20));
}

TEST(TransientGrid, ForgetsCellsOlderThanItsMemoryAsItGrows) {
  TransientGrid grid(1.0, 50);
  grid.note(Eigen::Vector3f(0.5f, 0.5f, 0.0f), 0);
  EXPECT_TRUE(grid.confirmed(Eigen::Vector3f(0.5f, 0.5f, 0.0f), 100, 20));
  // Ten thousand new cells, far later: the table grows and drops the old cell.
  std::vector<std::uint64_t> keys;
  for (int x = 0; x < 100; ++x) {
    for (int y = 0; y < 100; ++y) {
      keys.push_back(grid.key(
          Eigen::Vector3f(10.5f + static_cast<float>(x), static_cast<float>(y) + 0.5f, 0.0f)));
    }
  }
  grid.note(keys, 1000);
  EXPECT_FALSE(grid.confirmed(Eigen::Vector3f(0.5f, 0.5f, 0.0f), 100, 20));
  EXPECT_EQ(grid.size(), 10000u);
  // Later still, forty thousand more: the table grows again and drops the ten thousand, so
  // memory follows the recent scans, not the whole run.
  keys.clear();
  for (int x = 0; x < 200; ++x) {
    for (int y = 0; y < 200; ++y) {
      keys.push_back(grid.key(
          Eigen::Vector3f(-200.5f - static_cast<float>(x), static_cast<float>(y) + 0.5f, 0.0f)));
    }
  }
  grid.note(keys, 2000);
  EXPECT_EQ(grid.size(), 40000u);
  EXPECT_FALSE(grid.confirmed(Eigen::Vector3f(10.5f, 0.5f, 0.0f), 900, 20));
  EXPECT_TRUE(grid.confirmed(Eigen::Vector3f(-200.5f, 0.5f, 0.0f), 1900, 20));
}

TEST(TransientGrid, IgnoresPointsWithoutACellAndRejectsABadCell) {
  TransientGrid grid(0.15, 600);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  for (const Eigen::Vector3f& p :
       {Eigen::Vector3f(nan, 0.0f, 0.0f), Eigen::Vector3f(0.0f, inf, 0.0f),
        Eigen::Vector3f(1e9f, 0.0f, 0.0f)}) {
    EXPECT_EQ(grid.key(p), TransientGrid::kNoCell);
    grid.note(p, 0);
    EXPECT_FALSE(grid.confirmed(p, 100, 1));
  }
  EXPECT_EQ(grid.size(), 0u);
  EXPECT_THROW(TransientGrid(0.0, 600), core::ConfigError);
  EXPECT_THROW(TransientGrid(std::numeric_limits<double>::quiet_NaN(), 600), core::ConfigError);
}

}  // namespace
}  // namespace ringtrack::mapping
