#include "ringtrack/eval/statistics.hpp"

#include <gtest/gtest.h>

namespace ringtrack::eval {
namespace {

TEST(Quantile, NearestRankOnHandMadeSeries) {
  // Sorted: 1 2 3 4 5 6 7 8 9 10 (given shuffled); rank = round(q * 9).
  const std::vector<double> v = {7, 3, 10, 1, 5, 9, 2, 8, 4, 6};
  EXPECT_EQ(quantile(v, 0.0), 1.0);
  EXPECT_EQ(quantile(v, 0.5), 6.0);    // round(4.5) = 5 -> sixth value
  EXPECT_EQ(quantile(v, 0.95), 10.0);  // round(8.55) = 9
  EXPECT_EQ(quantile(v, 1.0), 10.0);
  EXPECT_EQ(quantile({}, 0.5), 0.0);
  EXPECT_EQ(quantile({4.25}, 0.95), 4.25);
}

}  // namespace
}  // namespace ringtrack::eval
