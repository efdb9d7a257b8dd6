#include "ringtrack/core/background_range.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "ringtrack/core/error.hpp"

namespace ringtrack::core {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// A 3-ring, 36-column sensor: small enough to script every cell.
SensorModel small_model() {
  return SensorModel::generic({-2, 0, 2}, 36);
}

OrganizedScan uniform_scan(const SensorModel& m, float wall_m) {
  OrganizedScan s(m.rings(), m.columns());
  s.set_uniform_columns(m, 0);
  for (int r = 0; r < m.rings(); ++r) {
    for (int c = 0; c < m.columns(); ++c) s.set_range(m, r, c, wall_m, 1.0f);
  }
  return s;
}

BackgroundRangeConfig config(int learn, int behind) {
  BackgroundRangeConfig cfg;
  cfg.scans_to_learn = learn;
  cfg.scans_to_learn_behind = behind;
  cfg.smoothing = 0.0;
  return cfg;
}

TEST(BackgroundRange, StaticWallIsLearnedAfterNScans) {
  const auto m = small_model();
  BackgroundRangeModel bg(m, config(5, 2));
  EXPECT_EQ(bg.size(), 3u * 36u);
  const auto wall = uniform_scan(m, 10.0f);
  for (int k = 0; k < 4; ++k) bg.update(wall);
  EXPECT_TRUE(std::isnan(bg.background_range(7)));
  EXPECT_FALSE(bg.is_in_front(7, 3.0, 0.2));  // nothing learned: no evidence
  EXPECT_EQ(bg.learned_count(), 0u);
  bg.update(wall);
  EXPECT_FLOAT_EQ(bg.background_range(7), 10.0f);
  EXPECT_EQ(bg.learned_count(), bg.size());
  EXPECT_TRUE(bg.is_in_front(7, 9.5, 0.2));
  EXPECT_FALSE(bg.is_in_front(7, 9.9, 0.2));
  EXPECT_FALSE(bg.is_in_front(7, 12.0, 0.2));
  EXPECT_EQ(bg.scans(), 5);
}

TEST(BackgroundRange, PersonWalkingThroughStaysForeground) {
  const auto m = small_model();
  BackgroundRangeModel bg(m, config(5, 2));
  const auto wall = uniform_scan(m, 10.0f);
  for (int k = 0; k < 5; ++k) bg.update(wall);
  // A person at 3 m, two columns wide, moving one column per scan across columns 0..20: each
  // cell sees the person for two consecutive scans.
  for (int k = 0; k < 20; ++k) {
    auto s = wall;
    for (int r = 0; r < 3; ++r) {
      s.set_range(m, r, k, 3.0f, 1.0f);
      s.set_range(m, r, k + 1, 3.0f, 1.0f);
    }
    bg.update(s);
    EXPECT_TRUE(bg.is_in_front(s, s.index(1, k), 0.5));
    EXPECT_FALSE(bg.is_in_front(s, s.index(1, k + 5), 0.5));
  }
  for (std::size_t i = 0; i < bg.size(); ++i) EXPECT_FLOAT_EQ(bg.background_range(i), 10.0f);
  // A person who stops for fewer than scans_to_learn scans, leaves and comes back stays
  // foreground too: the wall in between ends the streak.
  for (int round = 0; round < 3; ++round) {
    auto s = wall;
    s.set_range(m, 1, 30, 4.0f, 1.0f);
    for (int k = 0; k < 4; ++k) bg.update(s);
    bg.update(wall);
  }
  EXPECT_FLOAT_EQ(bg.background_range(wall.index(1, 30)), 10.0f);
}

TEST(BackgroundRange, ParkedObjectBecomesBackgroundAndLeaves) {
  const auto m = small_model();
  BackgroundRangeModel bg(m, config(6, 3));
  const auto wall = uniform_scan(m, 10.0f);
  for (int k = 0; k < 6; ++k) bg.update(wall);
  auto parked = wall;
  for (int c = 10; c < 14; ++c) parked.set_range(m, 0, c, 6.0f, 1.0f);
  const auto cell = parked.index(0, 11);
  for (int k = 0; k < 5; ++k) {
    bg.update(parked);
    EXPECT_FLOAT_EQ(bg.background_range(cell), 10.0f) << k;
    EXPECT_TRUE(bg.is_in_front(parked, cell, 0.5));
  }
  bg.update(parked);  // the sixth scan
  EXPECT_FLOAT_EQ(bg.background_range(cell), 6.0f);
  EXPECT_FALSE(bg.is_in_front(parked, cell, 0.5));
  // A person in front of the parked car is in front of the new background.
  EXPECT_TRUE(bg.is_in_front(cell, 3.0, 0.5));
  // The car drives away: the wall behind it returns after scans_to_learn_behind scans.
  bg.update(wall);
  bg.update(wall);
  EXPECT_FLOAT_EQ(bg.background_range(cell), 6.0f);
  bg.update(wall);
  EXPECT_FLOAT_EQ(bg.background_range(cell), 10.0f);
}

TEST(BackgroundRange, NoiseWithinToleranceIsOneSurface) {
  const auto m = small_model();
  BackgroundRangeConfig cfg = config(8, 3);
  cfg.smoothing = 0.1;
  BackgroundRangeModel bg(m, cfg);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> noise(-0.06f, 0.06f);  // +-6 cm, tolerance 15 cm + 1 %
  auto noisy = [&](float wall) {
    OrganizedScan s(m.rings(), m.columns());
    s.set_uniform_columns(m, 0);
    for (int r = 0; r < m.rings(); ++r) {
      for (int c = 0; c < m.columns(); ++c) s.set_range(m, r, c, wall + noise(rng), 1.0f);
    }
    return s;
  };
  for (int k = 0; k < 8; ++k) bg.update(noisy(10.0f));
  EXPECT_EQ(bg.learned_count(), bg.size());
  for (int k = 0; k < 50; ++k) {
    auto s = noisy(10.0f);
    if (k % 7 == 0) s.set_range(m, 2, 20, 4.0f, 1.0f);              // a flickering outlier in front
    if (k % 5 == 0) s.set_invalid(2, 21, ReturnStatus::kNoReturn);  // a dropout
    bg.update(s);
  }
  for (std::size_t i = 0; i < bg.size(); ++i) EXPECT_NEAR(bg.background_range(i), 10.0f, 0.06);
  // Beyond the tolerance is another surface.
  EXPECT_TRUE(bg.is_in_front(5, 9.5, 0.2));
}

TEST(BackgroundRange, SkyLearnsAnOpenBackgroundAndTooCloseIsIgnored) {
  const auto m = small_model();
  BackgroundRangeModel bg(m, config(3, 2));
  OrganizedScan sky(m.rings(), m.columns());
  sky.set_uniform_columns(m, 0);
  sky.set_invalid(0, 0, ReturnStatus::kTooClose);
  for (int k = 0; k < 3; ++k) bg.update(sky);
  EXPECT_TRUE(std::isinf(bg.background_range(sky.index(2, 4))));
  EXPECT_TRUE(bg.is_in_front(sky.index(2, 4), 50.0, 0.5));
  EXPECT_TRUE(std::isnan(bg.background_range(0)));  // only too-close returns: nothing learned

  BackgroundRangeConfig no_sky = config(3, 2);
  no_sky.learn_no_return = false;
  BackgroundRangeModel bg2(m, no_sky);
  for (int k = 0; k < 3; ++k) bg2.update(sky);
  EXPECT_EQ(bg2.learned_count(), 0u);
}

// Real captures: the column count and start azimuth vary from scan to scan; cells follow the
// azimuth, not the column index.
TEST(BackgroundRange, CellsFollowAzimuthNotColumnIndex) {
  const auto m = SensorModel::vlp16();
  BackgroundRangeModel bg(m, config(4, 2));
  const double step = m.azimuth_step_rad();
  std::mt19937 rng(9);
  std::uniform_int_distribution<int> start(0, 1807);
  const int target_bin = 400;
  for (int k = 0; k < 4; ++k) {
    const int first = start(rng);
    const int n = 1808 + (k % 2);
    OrganizedScan s(m.rings(), n);
    for (int c = 0; c < n; ++c) {
      s.column_azimuth_rad[static_cast<std::size_t>(c)] = (first + c + 0.05 * (k % 3 - 1)) * step;
      const int bin = (first + c) % 1808;
      for (int r = 0; r < 16; ++r) s.set_range(m, r, c, bin == target_bin ? 3.0f : 20.0f, 1.0f);
    }
    bg.update(s);
    const auto i = s.index(5, (target_bin - first + 1808) % 1808);
    EXPECT_EQ(bg.cell_of(s, i), static_cast<std::size_t>(5 * 1808 + target_bin));
  }
  EXPECT_FLOAT_EQ(bg.background_range(5 * 1808 + target_bin), 3.0f);
  EXPECT_FLOAT_EQ(bg.background_range(5 * 1808 + target_bin + 1), 20.0f);
  // With uniform columns a model cell is the scan index.
  OrganizedScan u(m.rings(), m.columns());
  u.set_uniform_columns(m, 0);
  for (std::size_t i = 0; i < u.size(); i += 97) EXPECT_EQ(bg.cell_of(u, i), i);
  EXPECT_EQ(bg.cell_of(u, u.index(0, 0)), 0u);
  (void)kDeg;
}

TEST(BackgroundRange, RejectsBadConfigAndScans) {
  const auto m = small_model();
  BackgroundRangeConfig cfg;
  cfg.scans_to_learn = 0;
  try {
    BackgroundRangeModel bad(m, cfg);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("scans_to_learn"), std::string::npos);
  }
  cfg = {};
  cfg.tolerance_m = -1;
  EXPECT_THROW(BackgroundRangeModel(m, cfg), ConfigError);
  cfg = {};
  cfg.smoothing = 2;
  EXPECT_THROW(BackgroundRangeModel(m, cfg), ConfigError);
  BackgroundRangeModel ok(m);
  EXPECT_THROW(ok.update(OrganizedScan(16, 36)), InputError);
}

// The rules of docs/visibility.md ("BackgroundRangeModel") cell by cell, written for clarity: the
// reference the model's inlined per-cell loop must match exactly.
class NaiveBackground {
 public:
  NaiveBackground(std::size_t cells, const BackgroundRangeConfig& cfg)
      : cfg_(cfg), bg_(cells, std::nanf("")), cand_(cells, std::nanf("")), streak_(cells, 0) {}

  void observe(std::size_t cell, ReturnStatus status, float range) {
    if (status == ReturnStatus::kTooClose) return;
    if (status != ReturnStatus::kValid) {
      if (!cfg_.learn_no_return) return;
      range = std::numeric_limits<float>::infinity();
    }
    float& bg = bg_[cell];
    float& cand = cand_[cell];
    int& streak = streak_[cell];
    const bool learned = !std::isnan(bg);
    if (learned && same(range, bg)) {
      if (std::isfinite(bg)) bg += static_cast<float>(cfg_.smoothing) * (range - bg);
      streak = 0;
      return;
    }
    if (streak > 0 && same(range, cand)) {
      if (std::isfinite(cand)) cand += (range - cand) / static_cast<float>(streak + 1);
      streak = std::min(streak + 1, 60000);
    } else {
      cand = range;
      streak = 1;
    }
    if (streak >= (learned && cand > bg ? cfg_.scans_to_learn_behind : cfg_.scans_to_learn)) {
      bg = cand;
      streak = 0;
    }
  }
  [[nodiscard]] float background(std::size_t cell) const { return bg_[cell]; }

 private:
  [[nodiscard]] bool same(float a, float b) const {
    if (std::isinf(a) || std::isinf(b)) return a == b;
    return std::abs(a - b) <= cfg_.tolerance_m + cfg_.relative_tolerance * std::min(a, b);
  }
  BackgroundRangeConfig cfg_;
  std::vector<float> bg_, cand_;
  std::vector<int> streak_;
};

// Random scans (a noisy wall, walkers in front, a parked object that comes and goes, sky,
// dropouts, too-close returns) through the model and the naive reference give the same
// background, bit for bit, after every scan.
TEST(BackgroundRange, MatchesTheNaiveReferenceCellByCell) {
  const auto m = small_model();
  for (const bool learn_open : {true, false}) {
    BackgroundRangeConfig cfg = config(6, 3);
    cfg.smoothing = 0.05;
    cfg.learn_no_return = learn_open;
    BackgroundRangeModel model(m, cfg);
    NaiveBackground naive(model.size(), cfg);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> noise(-0.1f, 0.1f);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    for (int k = 0; k < 300; ++k) {
      OrganizedScan s(m.rings(), m.columns());
      s.set_uniform_columns(m, 0);
      for (int r = 0; r < m.rings(); ++r) {
        for (int c = 0; c < m.columns(); ++c) {
          const float u = unit(rng);
          const bool parked = c >= 10 && c < 14 && (k / 40) % 2 == 1;
          if (r == 2 && c < 6) {
            s.set_invalid(r, c, ReturnStatus::kNoReturn);  // sky
          } else if (u < 0.03f) {
            s.set_invalid(r, c, u < 0.01f ? ReturnStatus::kTooClose : ReturnStatus::kTooFar);
          } else if (u < 0.08f) {
            s.set_range(m, r, c, 2.0f + 6.0f * unit(rng), 1.0f);  // a walker in front
          } else {
            s.set_range(m, r, c, (parked ? 5.0f : 10.0f) + noise(rng), 1.0f);
          }
        }
      }
      model.update(s);
      for (std::size_t i = 0; i < s.size(); ++i) {
        naive.observe(i, s.statuses()[i], s.ranges()[i]);
      }
      for (std::size_t i = 0; i < model.size(); ++i) {
        const float a = model.background_range(i), b = naive.background(i);
        ASSERT_TRUE(a == b || (std::isnan(a) && std::isnan(b)))
            << "scan " << k << " cell " << i << ": " << a << " vs " << b;
      }
    }
    EXPECT_GT(model.learned_count(), model.size() / 2);
  }
}

// The same, with whole blocks of neighbouring cells switching between a wall, open sky (no
// return, too far) and mixtures scan by scan, and the columns' azimuths rotated so that the
// cells are not the scan indices and one block of columns wraps around the bins: the model's
// four-cell fast path (common blocks) and its cell-by-cell path (every other block) against the
// reference.
TEST(BackgroundRange, MatchesTheNaiveReferenceAsBlocksSwitchBetweenWallAndSky) {
  const auto m = small_model();
  for (const int rotate : {0, 5}) {
    BackgroundRangeConfig cfg = config(4, 3);
    cfg.smoothing = 0.1;
    cfg.learn_no_return = true;
    BackgroundRangeModel model(m, cfg);
    NaiveBackground naive(model.size(), cfg);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> noise(-0.05f, 0.05f);
    std::uniform_int_distribution<int> odd(0, 40);
    for (int k = 0; k < 240; ++k) {
      OrganizedScan s(m.rings(), m.columns());
      s.set_uniform_columns(m, 0);
      std::rotate(s.column_azimuth_rad.begin(), s.column_azimuth_rad.begin() + rotate,
                  s.column_azimuth_rad.end());
      for (int r = 0; r < m.rings(); ++r) {
        for (int c = 0; c < m.columns(); ++c) {
          const int block = c / 4;
          const int regime = (k / (6 + block + r)) % 4;
          const int o = odd(rng);
          if (regime == 0 || (regime == 3 && o == 0)) {
            s.set_range(m, r, c, 8.0f + 0.5f * static_cast<float>(block) + noise(rng), 1.0f);
          } else if (regime == 1 || o == 1) {
            s.set_invalid(r, c, ReturnStatus::kNoReturn);
          } else if (regime == 2 || o == 2) {
            s.set_invalid(r, c, ReturnStatus::kTooFar);
          } else {
            s.set_range(m, r, c, 3.0f + noise(rng), 1.0f);  // something in front
          }
        }
      }
      model.update(s);
      for (std::size_t i = 0; i < s.size(); ++i) {
        naive.observe(model.cell_of(s, i), s.statuses()[i], s.ranges()[i]);
      }
      for (std::size_t i = 0; i < model.size(); ++i) {
        const float a = model.background_range(i), b = naive.background(i);
        ASSERT_TRUE(a == b || (std::isnan(a) && std::isnan(b)))
            << "rotate " << rotate << " scan " << k << " cell " << i << ": " << a << " vs " << b;
      }
    }
  }
}

}  // namespace
}  // namespace ringtrack::core
