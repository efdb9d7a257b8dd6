// The median windows' histogram against a sorted multiset (the naive reference).

#include "ringtrack/segmentation/order_stat_window.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace ringtrack::segmentation::detail {
namespace {

TEST(OrderStatWindow, BoundsAndRanksMatchASortedMultiset) {
  constexpr std::uint32_t kBuckets = 3000;
  std::mt19937 rng(17);
  // Clustered keys (a surface) with outliers (objects, sky), like ranges in a ring.
  std::vector<std::uint32_t> keys(20000);
  std::normal_distribution<double> cluster(1500.0, 40.0);
  std::uniform_int_distribution<std::uint32_t> any(0, kBuckets - 1);
  std::bernoulli_distribution outlier(0.2);
  for (auto& k : keys) {
    k = outlier(rng) ? any(rng)
                     : static_cast<std::uint32_t>(std::clamp(cluster(rng), 0.0, kBuckets - 1.0));
  }
  OrderStatWindow window(kBuckets);
  int left = 0, right = -1;  // the window holds keys[left..right]
  auto sorted = [&] {
    std::vector<std::uint32_t> s(keys.begin() + left, keys.begin() + right + 1);
    std::sort(s.begin(), s.end());
    return s;
  };
  std::uniform_int_distribution<int> width(1, 400), step(1, 60);
  while (right + 500 < static_cast<int>(keys.size())) {
    // Move: either a same-width shift (replace) or a reshape by separate adds and removes.
    const int s = step(rng);
    if (right >= left && rng() % 2 == 0) {
      window.replace(keys.data() + left, keys.data() + right + 1, std::min(s, right - left + 1));
      const int moved = std::min(s, right - left + 1);
      left += moved;
      right += moved;
    } else {
      const int new_left = left + s, new_right = new_left + width(rng) - 1;
      if (right >= left)
        window.update<-1>(keys.data() + left, keys.data() + std::min(right + 1, new_left));
      const int keep_to = std::min(right, new_right);
      if (right > new_right)
        window.update<-1>(keys.data() + new_right + 1, keys.data() + right + 1);
      const int add_from = std::max(keep_to + 1, new_left);
      window.update<1>(keys.data() + add_from, keys.data() + new_right + 1);
      left = new_left;
      right = new_right;
    }
    const auto s_keys = sorted();
    const int n = static_cast<int>(s_keys.size());
    ASSERT_EQ(window.size(), n);
    const int lo = std::uniform_int_distribution<int>(0, n - 1)(rng);
    const int hi = std::uniform_int_distribution<int>(lo, n - 1)(rng);
    window.set_ranks(lo, hi);
    // Lazy bounds: valid, not necessarily tight.
    ASSERT_LE(window.lo_bound_bucket(), s_keys[static_cast<std::size_t>(lo)]);
    ASSERT_GE(window.hi_bound_bucket(), s_keys[static_cast<std::size_t>(hi)]);
    // Tightened: exact.
    window.tighten();
    ASSERT_EQ(window.lo_bound_bucket(), s_keys[static_cast<std::size_t>(lo)]);
    ASSERT_EQ(window.hi_bound_bucket(), s_keys[static_cast<std::size_t>(hi)]);
    const int a = std::uniform_int_distribution<int>(0, n - 1)(rng);
    const auto tracked = window.track_rank(a);
    ASSERT_EQ(tracked.first, s_keys[static_cast<std::size_t>(a)]);
    ASSERT_EQ(tracked.second,
              std::lower_bound(s_keys.begin(), s_keys.end(), tracked.first) - s_keys.begin());
  }
}

}  // namespace
}  // namespace ringtrack::segmentation::detail
