// The pieces the fast segmenter's exactness rests on, each against the definition it replaces.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "ringtrack/segmentation/direct_median.hpp"
#include "ringtrack/segmentation/kernel.hpp"
#include "ringtrack/segmentation/radius_table.hpp"

namespace ringtrack::segmentation {
namespace {

float nth_median(std::vector<float> w) {
  const auto mid = w.begin() + static_cast<std::ptrdiff_t>(w.size() / 2);
  std::nth_element(w.begin(), mid, w.end());
  return *mid;
}

TEST(DirectMedian, EqualsSelectionForEveryOrderAndTie) {
  // Every assignment of 5 values from {1..5} covers every ordering and every pattern of ties.
  std::array<float, 5> w{};
  for (int code = 0; code < 5 * 5 * 5 * 5 * 5; ++code) {
    int rest = code;
    for (auto& x : w) {
      x = static_cast<float>(rest % 5 + 1);
      rest /= 5;
    }
    for (int r = 0; r <= detail::kDirectRadius; ++r) {
      const float* centre = w.data() + 2;
      const std::vector<float> window(centre - r, centre + r + 1);
      ASSERT_EQ(detail::direct_median(centre, r), nth_median(window)) << "code " << code;
    }
  }
}

// certainty(d) >= threshold for floats around x, compared with the rule's intervals.
void expect_rule_agrees_near(const DeltaRule& rule, const core::SegmentationConfig& c, float x) {
  float d = x;
  for (int i = 0; i < 4; ++i) d = std::nextafter(d, -std::numeric_limits<float>::infinity());
  for (int i = 0; i < 9; ++i, d = std::nextafter(d, std::numeric_limits<float>::infinity())) {
    const bool segment = certainty(d, c) >= c.certainty_threshold;
    if (d >= rule.segment_from && d <= rule.segment_to) {
      EXPECT_TRUE(segment) << d << " in [" << rule.segment_from << ", " << rule.segment_to << "]";
    }
    if (d < rule.background_below || d > rule.background_above) {
      EXPECT_FALSE(segment) << d << " outside [" << rule.background_below << ", "
                            << rule.background_above << "]";
    }
  }
}

TEST(DeltaRule, IsExactForTheDefaultsAndRandomConfigs) {
  core::SegmentationConfig c;
  auto rule = delta_rule(c);
  // The default threshold 0.5 on the ramp 0.1..0.3 m: segments from 0.2 m on.
  EXPECT_NEAR(rule.segment_from, 0.2f, 1e-6f);
  EXPECT_EQ(rule.background_below, rule.segment_from);
  EXPECT_EQ(rule.background_above, rule.segment_to);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 3.0), t(1e-6, 1.0);
  for (int trial = 0; trial < 300; ++trial) {
    std::array<double, 4> v{u(rng), u(rng), u(rng), u(rng)};
    std::sort(v.begin(), v.end());
    if (trial % 5 == 0) v[1] = v[0];  // vertical rising edge
    if (trial % 7 == 0) v[2] = v[1];  // no plateau
    c.delta_min_m = v[0];
    c.delta_low_m = v[1];
    c.delta_high_m = v[2];
    c.delta_max_m = v[3];
    c.certainty_threshold = trial % 3 == 0 ? 1.0 : t(rng);
    rule = delta_rule(c);
    EXPECT_LE(rule.background_below, rule.segment_from);
    EXPECT_GE(rule.background_above, rule.segment_to);
    for (float x : {rule.segment_from, rule.segment_to, static_cast<float>(v[0]),
                    static_cast<float>(v[1]), static_cast<float>(v[2]), static_cast<float>(v[3])})
      expect_rule_agrees_near(rule, c, x);
    std::uniform_real_distribution<float> any(-2.0f, 4.0f);
    for (int i = 0; i < 200; ++i) expect_rule_agrees_near(rule, c, any(rng));
  }
}

TEST(RadiusTable, ValueBoundsMatchTheFormula) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> logu(-4.0f, 9.0f);
  for (double width : {0.1, 1.2}) {
    for (bool up : {false, true}) {
      const KernelRadius formula{width, 2 * std::numbers::pi / 1800, up, 450};
      const detail::RadiusTable table(formula);
      for (int i = 0; i < 20000; ++i) {
        const float v = std::exp2(logu(rng));
        const int r = formula(v);
        for (int k : {0, 1, 2, r - 1, r, r + 1, 449, 450, 451}) {
          if (k < 0) continue;
          ASSERT_EQ(r <= k, v > table.radius_at_most_above(k)) << v << " k " << k;
          ASSERT_EQ(r >= k, v <= table.radius_at_least_up_to(k)) << v << " k " << k;
        }
      }
    }
  }
}

}  // namespace
}  // namespace ringtrack::segmentation
