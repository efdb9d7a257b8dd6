// LoggedScan::remove_inside with per-block bounds against a plain test of every point, for
// points along rings (as logged) and in random order, with non-finite points among them.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "ringtrack/mapping/dynamic_object_filter.hpp"

namespace ringtrack::mapping {
namespace {

// Reference: every point tested.
std::size_t naive_remove_inside(LoggedScan& scan, const core::Box3& box) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < scan.points.size(); ++i) {
    if (!scan.removed[i] && box.contains(scan.points[i])) {
      scan.removed[i] = 1;
      ++n;
    }
  }
  scan.removed_count += n;
  return n;
}

// 16 rings of 900 points on a wall 8-12 m away, the last block partly filled.
LoggedScan ring_scan(std::mt19937_64& rng, bool shuffle) {
  LoggedScan scan;
  std::uniform_real_distribution<float> wall(8.0f, 12.0f);
  for (int ring = 0; ring < 16; ++ring) {
    for (int c = 0; c < 900; ++c) {
      const float a = 2.0f * std::numbers::pi_v<float> * static_cast<float>(c) / 900.0f;
      const float r = wall(rng);
      scan.points.emplace_back(r * std::cos(a), r * std::sin(a),
                               -1.0f + 0.2f * static_cast<float>(ring));
    }
  }
  scan.points.resize(scan.points.size() - 17);
  scan.points[100] = Eigen::Vector3f(std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f);
  scan.points[5000] = Eigen::Vector3f::Constant(std::numeric_limits<float>::infinity());
  if (shuffle) std::shuffle(scan.points.begin(), scan.points.end(), rng);
  scan.removed.assign(scan.points.size(), 0);
  return scan;
}

void check_against_naive(bool shuffle, bool bounds) {
  std::mt19937_64 rng(shuffle ? 21 : 22);
  LoggedScan fast = ring_scan(rng, shuffle);
  LoggedScan naive = fast;
  if (bounds) fast.update_bounds();
  ASSERT_EQ(fast.block_bounds.size(), bounds ? (fast.points.size() + 63) / 64 : 0u);
  std::uniform_real_distribution<float> centre(-12.0f, 12.0f);
  std::uniform_real_distribution<float> half(0.1f, 3.0f);
  std::size_t total = 0;
  for (int k = 0; k < 200; ++k) {
    const Eigen::Vector3f c(centre(rng), centre(rng), centre(rng) * 0.2f);
    const Eigen::Vector3f h(half(rng), half(rng), half(rng));
    const core::Box3 box{c - h, c + h};
    const std::size_t removed = fast.remove_inside(box);
    ASSERT_EQ(removed, naive_remove_inside(naive, box)) << "box " << k;
    total += removed;
  }
  EXPECT_EQ(fast.removed, naive.removed);
  EXPECT_EQ(fast.removed_count, naive.removed_count);
  EXPECT_GT(total, 1000u);  // the boxes did hit the wall
  // An empty box removes nothing; a box around everything removes every finite point left.
  EXPECT_EQ(fast.remove_inside(core::Box3{}), 0u);
  const core::Box3 all{Eigen::Vector3f::Constant(-100.0f), Eigen::Vector3f::Constant(100.0f)};
  EXPECT_EQ(fast.remove_inside(all), naive_remove_inside(naive, all));
  EXPECT_EQ(fast.removed_count, fast.points.size() - 2);
}

TEST(LoggedScan, BlockBoundsRemoveTheSamePointsAlongRings) {
  check_against_naive(false, true);
}

TEST(LoggedScan, BlockBoundsRemoveTheSamePointsInRandomOrder) {
  check_against_naive(true, true);
}

TEST(LoggedScan, WithoutBoundsEveryPointIsTested) {
  check_against_naive(false, false);
}

TEST(LoggedScan, StaleBoundsAreNotUsed) {
  // Bounds computed for fewer points than the scan has now are ignored, not trusted (here the
  // new point falls into the last block, whose bounds do not cover it).
  std::mt19937_64 rng(23);
  LoggedScan scan = ring_scan(rng, false);
  scan.update_bounds();
  scan.points.emplace_back(50.0f, 50.0f, 0.0f);  // beyond every block's bounds
  scan.removed.push_back(0);
  EXPECT_EQ(scan.remove_inside({{49.0f, 49.0f, -1.0f}, {51.0f, 51.0f, 1.0f}}), 1u);
}

}  // namespace
}  // namespace ringtrack::mapping
