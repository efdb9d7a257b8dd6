// Map metrics from per-point labels.

#include "ringtrack/eval/map_metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "ringtrack/core/error.hpp"

namespace ringtrack::eval {
namespace {

TEST(MapMetrics, HandCountedCloud) {
  // Labels: 0 background, 3 a standing (static) person, 7 a walking (dynamic) person.
  const std::vector<std::int64_t> labels = {0, 0, 0, 0, 3, 3, 7, 7, 7, 7};
  const std::vector<std::uint8_t> kept = {1, 1, 1, 0, 1, 0, 0, 0, 0, 1};
  const std::vector<std::int64_t> dynamic = {7};
  const MapCounts c = count_map_points(labels, kept, dynamic);
  EXPECT_EQ(c.static_points, 6);
  EXPECT_EQ(c.static_kept, 4);
  EXPECT_EQ(c.dynamic_points, 4);
  EXPECT_EQ(c.dynamic_removed, 3);
  EXPECT_DOUBLE_EQ(c.preservation_rate(), 4.0 / 6.0);
  EXPECT_DOUBLE_EQ(c.rejection_rate(), 0.75);
}

TEST(MapMetrics, SumsOverScans) {
  MapCounts total;
  total.add_point(0, false, true);
  total.add_point(5, true, true);
  MapCounts other;
  other.add_point(5, true, false);
  other.add_point(0, true, false);  // label 0 is background whatever the flag says
  total += other;
  EXPECT_EQ(total.static_points, 2);
  EXPECT_EQ(total.static_kept, 1);
  EXPECT_EQ(total.dynamic_points, 2);
  EXPECT_EQ(total.dynamic_removed, 1);
  EXPECT_DOUBLE_EQ(total.rejection_rate(), 0.5);
}

TEST(MapMetrics, UndefinedRatesAndErrors) {
  const MapCounts none;
  EXPECT_TRUE(std::isnan(none.preservation_rate()));
  EXPECT_TRUE(std::isnan(none.rejection_rate()));
  const std::vector<std::int64_t> labels = {0, -1};
  const std::vector<std::uint8_t> kept = {1, 1};
  EXPECT_THROW((void)count_map_points(labels, kept, {}), core::InputError);
  EXPECT_THROW((void)count_map_points(labels, std::vector<std::uint8_t>{1}, {}), core::InputError);
}

}  // namespace
}  // namespace ringtrack::eval
