#include "ringtrack/segmentation/segmenter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/segmentation/kernel.hpp"
#include "ringtrack/segmentation/radius_table.hpp"
#include "ringtrack/sim/scenario.hpp"
#include "ringtrack/sim/simple_scene.hpp"
#include "ringtrack/sim/simulator.hpp"
#include "support/naive_segmentation.hpp"

namespace ringtrack::segmentation {
namespace {

using core::OrganizedScan;
using core::SegmentationConfig;

// A scan filled from a range function; NaN gives an invalid cell.
template <class F>
OrganizedScan scan_from(int rings, int columns, F range_of) {
  OrganizedScan s(rings, columns);
  const auto model = core::SensorModel::generic(
      std::vector<double>(static_cast<std::size_t>(rings), 0.0), columns);
  for (int r = 0; r < rings; ++r) {
    for (int c = 0; c < columns; ++c) {
      const float v = range_of(r, c);
      if (std::isnan(v)) continue;
      s.set_return(r, c, v, 1.0f, Eigen::Vector3f(v, 0, 0));
    }
  }
  return s;
}

void expect_matches_naive(const OrganizedScan& scan, const SegmentationConfig& config,
                          std::size_t* segments = nullptr) {
  Segmenter fast(config);
  std::vector<std::uint8_t> labels;
  fast.segment(scan, labels);
  const auto expected = testing::naive_segment(scan, config);
  ASSERT_EQ(labels.size(), expected.size());
  std::size_t mismatches = 0, count = 0;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    mismatches += labels[i] != expected[i];
    count += expected[i];
  }
  EXPECT_EQ(mismatches, 0u) << "of " << labels.size() << " cells, " << count << " segments";
  if (segments) *segments = count;
}

TEST(KernelRadius, TableEqualsFormulaEverywhere) {
  std::mt19937 rng(7);
  for (double width : {0.05, 0.1, 1.2, 3.0}) {
    for (bool up : {false, true}) {
      const KernelRadius formula{width, 2 * std::numbers::pi / 1809, up, 450};
      const detail::RadiusTable table(formula);
      std::uniform_real_distribution<float> u(0.01f, 300.0f);
      std::uniform_real_distribution<float> logu(-4.0f, 9.0f);
      for (int k = 0; k < 200000; ++k) {
        const float v = k % 2 ? u(rng) : std::exp2(logu(rng));
        ASSERT_EQ(table.radius(v, detail::RangeBuckets::key(v)), formula(v)) << v;
      }
      for (std::uint32_t b = 0; b < detail::RangeBuckets::kCount; b += 7) {
        const float v = std::max(detail::RangeBuckets::lower(b), 1e-3f);
        ASSERT_EQ(table.radius(v, detail::RangeBuckets::key(v)), formula(v)) << v;
      }
    }
  }
}

TEST(KernelRadius, PaperFormula) {
  // 1.2 m at 1 m with 0.2 deg steps: 2 atan(0.6) = 61.93 deg -> 309.6 -> ceil 310.
  const KernelRadius bg{1.2, 0.2 * std::numbers::pi / 180, true, 1000};
  EXPECT_EQ(bg(1.0f), 310);
  const KernelRadius noise{0.1, 0.2 * std::numbers::pi / 180, false, 1000};
  EXPECT_EQ(noise(10.0f), 2);  // 2 atan(0.005) = 0.573 deg -> 2.86 -> floor 2
  EXPECT_EQ(noise(100.0f), 0);
  EXPECT_EQ(KernelRadius(bg.width_m, bg.azimuth_step_rad, true, 50)(1.0f), 50);
}

TEST(Certainty, PiecewiseLinear) {
  SegmentationConfig c;
  c.delta_min_m = 0.1;
  c.delta_low_m = 0.3;
  c.delta_high_m = 1.0;
  c.delta_max_m = 2.0;
  EXPECT_DOUBLE_EQ(certainty(0.05f, c), 0.0);
  EXPECT_NEAR(certainty(0.2f, c), 0.5, 1e-6);
  EXPECT_DOUBLE_EQ(certainty(0.5f, c), 1.0);
  EXPECT_NEAR(certainty(1.5f, c), 0.5, 1e-6);
  EXPECT_DOUBLE_EQ(certainty(2.5f, c), 0.0);
}

TEST(Segmenter, PersonInFrontOfWallIsSegmentedAndWallIsNot) {
  // One ring, 1800 columns (0.2 deg), wall at 8 m, a 0.5 m wide object at 4 m around column 100.
  const int n = 1800;
  const int half = static_cast<int>(std::round(std::atan(0.25 / 4.0) / (2 * std::numbers::pi / n)));
  const auto scan =
      scan_from(1, n, [&](int, int c) { return std::abs(c - 100) <= half ? 4.0f : 8.0f; });
  Segmenter s(SegmentationConfig{});
  std::vector<std::uint8_t> labels;
  s.segment(scan, labels);
  for (int c = 0; c < n; ++c)
    EXPECT_EQ(labels[c], std::abs(c - 100) <= half ? kSegment : kBackground) << c;
}

TEST(Segmenter, ObjectAcrossTheSeamAndAgainstTheSky) {
  // The object straddles column 0; everything else is sky (no return).
  const int n = 1800;
  const auto scan =
      scan_from(1, n, [&](int, int c) { return (c <= 20 || c >= n - 20) ? 5.0f : std::nanf(""); });
  Segmenter s(SegmentationConfig{});
  std::vector<std::uint8_t> labels;
  s.segment(scan, labels);
  for (int c = 0; c < n; ++c)
    EXPECT_EQ(labels[c], (c <= 20 || c >= n - 20) ? kSegment : kBackground) << c;
}

TEST(Segmenter, ThinPoleAndWideWallAreNotSegments) {
  const int n = 1800;
  // Pole 1 column wide at 5 m (~1.7 cm), wall segment 200 columns (~3.5 m) at 5 m, background 10 m.
  const auto scan = scan_from(1, n, [&](int, int c) {
    if (c == 300) return 5.0f;
    if (c >= 900 && c < 1100) return 5.0f;
    return 10.0f;
  });
  Segmenter s(SegmentationConfig{});
  std::vector<std::uint8_t> labels;
  s.segment(scan, labels);
  EXPECT_EQ(labels[300], kBackground);
  for (int c = 900; c < 1100; ++c) EXPECT_EQ(labels[c], kBackground) << c;
}

TEST(Segmenter, MatchesNaiveOnRandomScans) {
  std::mt19937 rng(42);
  for (int trial = 0; trial < 6; ++trial) {
    std::uniform_real_distribution<float> u(0.3f, 120.0f);
    std::bernoulli_distribution missing(trial % 2 ? 0.3 : 0.02);
    const auto scan =
        scan_from(4, 1800, [&](int, int) { return missing(rng) ? std::nanf("") : u(rng); });
    expect_matches_naive(scan, SegmentationConfig{});
  }
}

TEST(Segmenter, MatchesNaiveOnAdversarialScans) {
  std::mt19937 rng(1);
  std::normal_distribution<float> noise(0.0f, 0.03f);
  SegmentationConfig config;
  // A wall 0.5-1 m away all around: kernels of hundreds of points.
  auto wall = scan_from(4, 1809, [&](int r, int c) {
    const float wall_m = 0.5f + 0.5f * static_cast<float>(r) / 3.0f;
    return wall_m + noise(rng) - ((c / 37) % 5 == 0 ? 0.3f : 0.0f);
  });
  std::size_t segments = 0;
  expect_matches_naive(wall, config, &segments);
  EXPECT_GT(segments, 0u);
  // Long runs of invalid returns between short objects, and range jumps of every size.
  auto gaps = scan_from(4, 1800, [&](int r, int c) {
    if ((c / 200) % 2 == 0) return std::nanf("");
    return (c % 23 < 3 + r) ? 2.0f + 0.01f * static_cast<float>(c % 7) : 30.0f + noise(rng);
  });
  expect_matches_naive(gaps, config);
  auto jumps = scan_from(4, 1800, [&](int r, int c) {
    const int block = (c * (r + 3)) / 17;
    return 0.4f + static_cast<float>((block * 7919) % 1000) * 0.1f;
  });
  expect_matches_naive(jumps, config);
  // Many exact ties: quantised ranges.
  std::uniform_int_distribution<int> q(1, 6);
  auto ties = scan_from(4, 1800, [&](int, int) { return 0.5f * static_cast<float>(q(rng)); });
  expect_matches_naive(ties, config);
  // Ambiguous differences right at the certainty ramp: objects 0.1-0.3 m in front of a wall.
  auto ramp = scan_from(4, 1800, [&](int r, int c) {
    return (c % 60 < 20) ? 3.0f - 0.1f - 0.02f * static_cast<float>(r + c % 11)
                         : 3.0f + noise(rng) * 0.1f;
  });
  expect_matches_naive(ramp, config);
}

TEST(Segmenter, MatchesNaiveOnRenderedScenesAndOtherConfigs) {
  const auto model = core::SensorModel::vlp16();
  for (const auto& scene :
       {sim::SimpleScene::hard_wall(), sim::SimpleScene::open_field(), sim::SimpleScene::demo()}) {
    const auto rendered = sim::render(model, scene);
    expect_matches_naive(rendered.scan, SegmentationConfig{});
    SegmentationConfig other;
    other.min_width_m = 0.3;
    other.max_width_m = 2.5;
    other.max_kernel_radius = 100;
    other.delta_high_m = 1.0;
    other.delta_max_m = 3.0;
    other.certainty_threshold = 0.9;
    expect_matches_naive(rendered.scan, other);
  }
}

// Random configurations within the schema's ranges that still mean something.
SegmentationConfig random_config(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  SegmentationConfig c;
  c.min_width_m = 0.02 + 0.4 * u(rng);
  c.max_width_m = c.min_width_m + 3.0 * u(rng);
  c.max_kernel_radius = 20 + static_cast<int>(600 * u(rng));
  c.delta_min_m = -0.2 + 0.5 * u(rng);
  c.delta_low_m = c.delta_min_m + 0.5 * u(rng);
  c.delta_high_m = c.delta_low_m + 5.0 * u(rng);
  c.delta_max_m = c.delta_high_m + 5.0 * u(rng);
  c.certainty_threshold = 0.01 + 0.99 * u(rng);
  return c;
}

TEST(Segmenter, MatchesNaiveOnPiecewiseSurfaces) {
  // Runs of flat and sloped surfaces, objects and gaps at every range, so the references jump,
  // their lazy bounds lag and the radius changes abruptly; with random configurations.
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  for (int trial = 0; trial < 24; ++trial) {
    std::vector<float> row(4 * 1800);
    std::size_t at = 0;
    while (at < row.size()) {
      const auto length = static_cast<std::size_t>(1 + std::pow(u(rng), 2.0f) * 400);
      const float range = 0.3f + std::pow(u(rng), 2.0f) * 120.0f;
      const float slope = u(rng) < 0.3f ? (u(rng) - 0.5f) * 0.05f * range : 0.0f;
      const float sigma = u(rng) * 0.05f;
      const bool gap = u(rng) < 0.1f;
      for (std::size_t k = 0; k < length && at < row.size(); ++k, ++at) {
        row[at] = gap ? std::nanf("")
                      : std::max(0.05f, range + slope * static_cast<float>(k) + sigma * noise(rng));
      }
    }
    const auto scan = scan_from(4, 1800, [&](int r, int c) { return row[r * 1800 + c]; });
    expect_matches_naive(scan, trial % 2 ? random_config(rng) : SegmentationConfig{});
  }
}

TEST(Segmenter, MatchesNaiveOnSimulatedScans) {
  for (const auto& scenario :
       {sim::builtin_scenario("park"), sim::with_moving_sensor(sim::builtin_scenario("park"))}) {
    sim::Simulator simulator(scenario, 3);
    std::mt19937 rng(9);
    for (int i = 0; i < 12; ++i) {
      const auto simulated = simulator.next();
      if (i % 4 != 3) continue;
      expect_matches_naive(simulated.scan, SegmentationConfig{});
      expect_matches_naive(simulated.scan, random_config(rng));
    }
  }
}

TEST(Segmenter, PeopleInRenderedScenesAreFound) {
  const auto model = core::SensorModel::vlp16();
  const auto rendered = sim::render(model, sim::SimpleScene::hard_wall());
  Segmenter s(SegmentationConfig{});
  std::vector<std::uint8_t> labels;
  s.segment(rendered.scan, labels);
  std::size_t person = 0, person_segment = 0, wall_segment = 0, wall = 0;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (!rendered.scan.valid(i)) continue;
    if (rendered.labels[i] != 0) {
      ++person;
      person_segment += labels[i];
    } else {
      ++wall;
      wall_segment += labels[i];
    }
  }
  EXPECT_GT(person_segment, person * 8 / 10);
  EXPECT_LT(wall_segment, wall / 50);
}

}  // namespace
}  // namespace ringtrack::segmentation
