#pragma once
/// Test support: comparing two sets of static-map voxels whose order differs (a map against a
/// reference, or what left a bounded map plus what stayed against the unbounded map).

#include <gtest/gtest.h>

#include <algorithm>
#include <tuple>
#include <vector>

#include "ringtrack/mapping/static_map.hpp"

namespace ringtrack::test {

/// Expects the same voxels (position, intensity, count exactly), whatever their order; where
/// names the comparison in failure messages.
inline void expect_same_map_points(std::vector<mapping::MapPoint> a,
                                   std::vector<mapping::MapPoint> b, const char* where) {
  const auto by_value = [](const mapping::MapPoint& p, const mapping::MapPoint& q) {
    return std::tie(p.position.x(), p.position.y(), p.position.z(), p.intensity, p.count) <
           std::tie(q.position.x(), q.position.y(), q.position.z(), q.intensity, q.count);
  };
  std::sort(a.begin(), a.end(), by_value);
  std::sort(b.begin(), b.end(), by_value);
  ASSERT_EQ(a.size(), b.size()) << where;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].position, b[i].position) << where << ", voxel " << i;
    ASSERT_EQ(a[i].intensity, b[i].intensity) << where << ", voxel " << i;
    ASSERT_EQ(a[i].count, b[i].count) << where << ", voxel " << i;
  }
}

}  // namespace ringtrack::test
