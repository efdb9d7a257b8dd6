// StaticMap's incremental table growth against a naive reference: a std::map from voxel index
// to the same running mean. Inserts (single and batched), removals with small boxes (voxel
// lookups), huge boxes (table scans) and discs (remove_outside) are checked before, during and
// after every resize, in both resize phases (the doubled table being prepared; the old table
// draining into it).

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <vector>

#include "ringtrack/mapping/static_map.hpp"
#include "support/map_points.hpp"

namespace ringtrack::mapping {
namespace {

// Reference: voxel index floor(p / size) per axis, mean of the first kSettledCount points.
class NaiveMap {
 public:
  explicit NaiveMap(double voxel_size_m) : inverse_(static_cast<float>(1.0 / voxel_size_m)) {}

  void insert(const Eigen::Vector3f& p, float intensity) {
    if (!p.allFinite()) return;
    const std::array<std::int64_t, 3> key{static_cast<std::int64_t>(std::floor(p.x() * inverse_)),
                                          static_cast<std::int64_t>(std::floor(p.y() * inverse_)),
                                          static_cast<std::int64_t>(std::floor(p.z() * inverse_))};
    MapPoint& m = voxels_[key];
    if (m.count >= StaticMap::kSettledCount) return;
    ++m.count;
    const float w = 1.0f / static_cast<float>(m.count);
    m.position += w * (p - m.position);
    m.intensity += w * (intensity - m.intensity);
  }

  std::size_t remove_inside(const core::Box3& box) {
    std::size_t n = 0;
    for (auto it = voxels_.begin(); it != voxels_.end();) {
      if (box.contains(it->second.position)) {
        it = voxels_.erase(it);
        ++n;
      } else {
        ++it;
      }
    }
    return n;
  }

  std::size_t remove_outside(const Eigen::Vector2f& center, float radius,
                             std::vector<MapPoint>& evicted) {
    std::size_t n = 0;
    for (auto it = voxels_.begin(); it != voxels_.end();) {
      if ((it->second.position.head<2>() - center).norm() > radius) {
        evicted.push_back(it->second);
        it = voxels_.erase(it);
        ++n;
      } else {
        ++it;
      }
    }
    return n;
  }

  [[nodiscard]] std::size_t size() const { return voxels_.size(); }
  // Ordered by voxel index, as StaticMap::points().
  [[nodiscard]] std::vector<MapPoint> points() const {
    std::vector<MapPoint> out;
    for (const auto& [key, point] : voxels_) out.push_back(point);
    return out;
  }

 private:
  float inverse_;
  std::map<std::array<std::int64_t, 3>, MapPoint> voxels_;
};

void expect_same(const StaticMap& map, const NaiveMap& reference, const char* where) {
  ASSERT_EQ(map.size(), reference.size()) << where;
  const auto a = map.points();
  const auto b = reference.points();
  ASSERT_EQ(a.size(), b.size()) << where;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].count, b[i].count) << where << ", voxel " << i;
    ASSERT_EQ(a[i].position, b[i].position) << where << ", voxel " << i;
    ASSERT_EQ(a[i].intensity, b[i].intensity) << where << ", voxel " << i;
  }
  std::size_t visited = 0;
  map.for_each([&](const MapPoint&) { ++visited; });
  EXPECT_EQ(visited, map.size()) << where;
}

// Which part of a resize the map is in, seen from outside: the doubled table is being prepared
// while the capacity is still the old one, and the old table drains once the capacity doubled.
struct PhaseLog {
  std::size_t idle_capacity = 0;
  int preparing = 0;
  int draining = 0;

  void observe(const StaticMap& map) {
    if (!map.resizing()) {
      idle_capacity = map.capacity();
    } else if (map.capacity() == idle_capacity) {
      ++preparing;
    } else {
      ++draining;
    }
  }
};

TEST(StaticMapResize, MatchesANaiveMapThroughManyResizes) {
  constexpr double kVoxel = 0.1;
  StaticMap map(kVoxel);
  NaiveMap reference(kVoxel);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<float> xy(-15.0f, 15.0f);
  std::uniform_real_distribution<float> z(0.0f, 0.5f);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<Eigen::Vector3f> history;  // earlier points, re-inserted to grow the counts
  PhaseLog log;
  log.observe(map);
  int removals_while_resizing = 0;
  int evictions = 0;  // remove_outside calls that removed something
  for (int batch = 0; batch < 300; ++batch) {
    std::vector<Eigen::Vector3f> points;
    std::vector<float> intensities;
    std::vector<std::uint8_t> skip;
    for (int i = 0; i < 300; ++i) {
      Eigen::Vector3f p(xy(rng), xy(rng), z(rng));
      if (!history.empty() && unit(rng) < 0.4f) {
        p = history[static_cast<std::size_t>(unit(rng) * 0.999f *
                                             static_cast<float>(history.size()))];
      }
      history.push_back(p);
      points.push_back(p);
      intensities.push_back(unit(rng) * 100.0f);
      skip.push_back(unit(rng) < 0.1f ? 1 : 0);
    }
    if (batch % 3 == 0) {
      // Point by point.
      for (std::size_t i = 0; i < points.size(); ++i) {
        if (!skip[i]) map.insert(points[i], intensities[i]);
        log.observe(map);
      }
    } else {
      map.insert(points, intensities, skip);
      log.observe(map);
    }
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (!skip[i]) reference.insert(points[i], intensities[i]);
    }
    ASSERT_EQ(map.size(), reference.size()) << "batch " << batch;
    if (batch % 4 == 1) {
      // A small box: voxel lookups, in whichever table the voxels sit.
      const Eigen::Vector3f c(xy(rng), xy(rng), 0.25f);
      const core::Box3 box{c.array() - 0.6f, c.array() + 0.6f};
      if (map.resizing()) ++removals_while_resizing;
      EXPECT_EQ(map.remove_inside(box), reference.remove_inside(box)) << "batch " << batch;
    }
    if (batch % 50 == 37) {
      // A box larger than the table: a scan of both tables.
      const core::Box3 box{{-15.0f, -15.0f, 0.0f}, {xy(rng), 15.0f, 0.5f}};
      if (map.resizing()) ++removals_while_resizing;
      EXPECT_EQ(map.remove_inside(box), reference.remove_inside(box)) << "batch " << batch;
    }
    if (batch % 7 == 3) {
      // Bounded memory (mapping.map_radius_m): the corners beyond a disc leave, handed over.
      const Eigen::Vector2f c(xy(rng) * 0.1f, xy(rng) * 0.1f);
      if (map.resizing()) ++removals_while_resizing;
      std::vector<MapPoint> evicted, expected;
      EXPECT_EQ(map.remove_outside(c, 20.0f, evicted), reference.remove_outside(c, 20.0f, expected))
          << "batch " << batch;
      test::expect_same_map_points(evicted, expected, "evicted");
      if (!expected.empty()) ++evictions;
    }
    if (batch % 10 == 0 || map.resizing()) expect_same(map, reference, "during the run");
    if (HasFatalFailure()) return;
  }
  expect_same(map, reference, "at the end");
  map.finish_resize();
  EXPECT_FALSE(map.resizing());
  expect_same(map, reference, "after finish_resize");
  // Every path was taken: the table grew from 2^10 slots past 2^16, with inserts and removals
  // in both phases.
  EXPECT_GE(map.capacity(), std::size_t{1} << 16);
  EXPECT_GT(log.preparing, 0);
  EXPECT_GT(log.draining, 0);
  EXPECT_GT(removals_while_resizing, 0);
  EXPECT_GT(evictions, 10);
}

TEST(StaticMapResize, VoxelsRemovedFromTheDrainingTableStayRemoved) {
  // Right after the capacity doubled nearly every voxel still sits in the old table (at load
  // near 1/2, so in runs of several slots): remove half of them there, then insert every point
  // again. Removed voxels start from scratch; the others, including those probed past a removed
  // slot, must still be found (count 2), never duplicated.
  constexpr double kVoxel = 0.5;
  StaticMap map(kVoxel);
  NaiveMap reference(kVoxel);
  const std::size_t start = map.capacity();
  std::vector<Eigen::Vector3f> points;
  while (map.capacity() == start || !map.resizing()) {
    const auto i = static_cast<int>(points.size());
    points.emplace_back(static_cast<float>(i % 40) * 0.5f + 0.25f,
                        static_cast<float>(i / 40) * 0.5f + 0.25f, 0.25f);
    map.insert(points.back(), 1.0f);
    reference.insert(points.back(), 1.0f);
    ASSERT_LT(points.size(), 100000u) << "the table never grew";
  }
  const core::Box3 box{{0.0f, 0.0f, 0.0f}, {10.0f, 1000.0f, 1.0f}};  // x < 10 m: half
  const std::size_t removed = map.remove_inside(box);
  EXPECT_EQ(removed, reference.remove_inside(box));
  EXPECT_GT(removed, points.size() / 3);
  EXPECT_TRUE(map.resizing());
  for (const auto& p : points) {
    map.insert(p, 50.0f);
    reference.insert(p, 50.0f);
  }
  expect_same(map, reference, "after inserting again");
  map.finish_resize();
  expect_same(map, reference, "after finish_resize");
}

TEST(StaticMapResize, GrowthIsSpreadOverManyInserts) {
  // A map growing by 1000 voxels per batch: every resize past the first small tables spans
  // many batches (no batch rehashes the whole table), the table never exceeds load 0.7, and the
  // voxels (stored in blocks partly reused from drained tables) match the naive map.
  StaticMap map(0.1);
  NaiveMap reference(0.1);
  int batches_resizing = 0;
  int longest_run = 0, run = 0;
  std::vector<Eigen::Vector3f> points(1000);
  const std::vector<float> intensities(points.size(), 1.0f);
  for (int batch = 0; batch < 400; ++batch) {
    for (std::size_t i = 0; i < points.size(); ++i) {
      const auto k = static_cast<std::size_t>(batch) * points.size() + i;
      points[i] = Eigen::Vector3f(static_cast<float>(k % 1000) * 0.1f + 0.05f,
                                  static_cast<float>(k / 1000) * 0.1f + 0.05f, 0.05f);
      reference.insert(points[i], intensities[i]);
    }
    map.insert(points, intensities, {});
    ASSERT_EQ(map.size(), static_cast<std::size_t>(batch + 1) * points.size());
    ASSERT_LE(10 * map.size(), 7 * map.capacity());
    if (map.resizing()) {
      ++batches_resizing;
      longest_run = std::max(longest_run, ++run);
    } else {
      run = 0;
    }
  }
  // 400 k voxels: the last completed resize (2^19 -> 2^20 slots) alone spans more than 50
  // batches; most batches carry a little resize work.
  EXPECT_EQ(map.capacity(), std::size_t{1} << 20);
  EXPECT_GT(longest_run, 50) << batches_resizing;
  expect_same(map, reference, "after growing to 400 k voxels");
}

TEST(StaticMapResize, RepeatedPointsFinishAPendingResize) {
  // A static sensor adds no new voxels; the pending resize still completes, driven by the points
  // inserted, and the map keeps its voxels.
  StaticMap map(0.1);
  std::vector<Eigen::Vector3f> points;
  int i = 0;
  while (!map.resizing()) {
    points.emplace_back(static_cast<float>(i % 200) * 0.1f + 0.05f,
                        static_cast<float>(i / 200) * 0.1f + 0.05f, 0.05f);
    map.insert(points.back(), 1.0f);
    ++i;
  }
  const std::size_t voxels = map.size();
  const std::vector<float> intensities(points.size(), 1.0f);
  int scans = 0;
  while (map.resizing()) {
    map.insert(points, intensities, {});
    ASSERT_LT(++scans, 1000) << "the resize never finished";
  }
  EXPECT_EQ(map.size(), voxels);
  const auto all = map.points();
  ASSERT_EQ(all.size(), voxels);
  for (const auto& p : all) EXPECT_EQ(p.count, static_cast<std::uint32_t>(scans + 1));
}

}  // namespace
}  // namespace ringtrack::mapping
