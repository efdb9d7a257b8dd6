// The batch insert computes its voxel keys with its own kernel (three axes at once, 32-bit lanes);
// the single-point insert and voxel_at() with the scalar one. Both must give every point the
// same voxel, std::floor's, on the awkward values: exact voxel boundaries, negative fractions,
// -0, the ends of the +-2^20 voxel index range, non-finite coordinates.

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <set>
#include <unordered_map>
#include <vector>

#include "ringtrack/mapping/static_map.hpp"

namespace ringtrack::mapping {
namespace {

constexpr double kVoxel = 0.1;

std::vector<float> awkward_coordinates() {
  const float inf = std::numeric_limits<float>::infinity();
  const float limit = static_cast<float>(1 << 20);  // voxel index range, in voxels
  std::vector<float> v{0.0f,
                       -0.0f,
                       std::numeric_limits<float>::denorm_min(),
                       -std::numeric_limits<float>::denorm_min(),
                       std::numeric_limits<float>::quiet_NaN(),
                       inf,
                       -inf,
                       std::numeric_limits<float>::max(),
                       std::numeric_limits<float>::lowest()};
  // Multiples of the voxel size (their scaled value rounds to either side of an integer), and
  // their neighbouring floats.
  for (int k = -40; k <= 40; ++k) {
    const float x = static_cast<float>(k) * static_cast<float>(kVoxel);
    v.push_back(x);
    v.push_back(std::nextafter(x, inf));
    v.push_back(std::nextafter(x, -inf));
  }
  // Around both ends of the index range (in metres: voxels times the voxel size).
  for (const float ends : {limit, -limit}) {
    for (const float d : {-2.0f, -1.0f, -0.5f, 0.0f, 0.5f, 1.0f}) {
      const float x = (ends + d) * static_cast<float>(kVoxel);
      v.push_back(x);
      v.push_back(std::nextafter(x, inf));
      v.push_back(std::nextafter(x, -inf));
    }
  }
  return v;
}

TEST(StaticMapKeys, BatchKeysMatchTheScalarKeys) {
  const auto coords = awkward_coordinates();
  std::mt19937 rng(11);
  std::uniform_int_distribution<std::size_t> pick(0, coords.size() - 1);
  std::uniform_real_distribution<float> wide(-150.0f, 150.0f);
  std::vector<Eigen::Vector3f> points;
  for (std::size_t i = 0; i < 20000; ++i) {
    Eigen::Vector3f p;
    for (int a = 0; a < 3; ++a) p[a] = (i % 3 == 0) ? wide(rng) : coords[pick(rng)];
    points.push_back(p);
  }
  // Every combination of three awkward coordinates along the first axis too.
  for (const float x : coords) points.emplace_back(x, 0.05f, -0.05f);
  const std::vector<float> intensities(points.size(), 1.0f);

  StaticMap batch(kVoxel);
  batch.insert(points, intensities, {});
  StaticMap single(kVoxel);
  for (std::size_t i = 0; i < points.size(); ++i) single.insert(points[i], intensities[i]);

  EXPECT_EQ(batch.dropped_points(), single.dropped_points());
  ASSERT_EQ(batch.size(), single.size());
  const auto a = batch.points();
  const auto b = single.points();
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].count, b[i].count) << "voxel " << i;
    ASSERT_EQ(a[i].position, b[i].position) << "voxel " << i;
  }

  // The voxels are std::floor's, and every point stored is found again in its voxel.
  const auto inverse = static_cast<float>(1.0 / kVoxel);
  std::set<std::array<std::int64_t, 3>> naive;
  std::size_t dropped = 0;
  for (const auto& p : points) {
    const Eigen::Vector3f s = p * inverse;
    if (!(s.array().abs() < static_cast<float>(1 << 20)).all()) {
      ++dropped;
      continue;
    }
    naive.insert({static_cast<std::int64_t>(std::floor(s.x())),
                  static_cast<std::int64_t>(std::floor(s.y())),
                  static_cast<std::int64_t>(std::floor(s.z()))});
    ASSERT_NE(batch.voxel_at(p), nullptr);
  }
  EXPECT_EQ(batch.dropped_points(), dropped);
  EXPECT_EQ(batch.size(), naive.size());
}

// The batch insert answers a point from the voxel its home slot named when the slot was
// prefetched, when the keys match, and looks it up otherwise. Points that revisit voxels in
// every pattern (runs of one voxel, alternations, voxels made earlier in the same chunk, new
// voxels among old ones), in maps young and large enough to resize, against single inserts.
TEST(StaticMapKeys, BatchLookupsMatchSingleInsertsOnRevisits) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> coord(-3.0f, 3.0f);
  std::uniform_int_distribution<int> pattern(0, 3);
  StaticMap batch(kVoxel);
  StaticMap single(kVoxel);
  std::vector<Eigen::Vector3f> seen;
  for (int scan = 0; scan < 60; ++scan) {
    std::vector<Eigen::Vector3f> points;
    while (points.size() < 3000) {
      const Eigen::Vector3f a(coord(rng), coord(rng), 0.3f * coord(rng));
      const Eigen::Vector3f b = seen.empty() ? a : seen[rng() % seen.size()];
      switch (pattern(rng)) {
        case 0:  // a run in one voxel
          for (int k = 0; k < 5; ++k) points.push_back(a);
          break;
        case 1:  // alternating between a new and an old voxel
          for (int k = 0; k < 6; ++k) points.push_back(k % 2 == 0 ? a : b);
          break;
        case 2:  // an old voxel again
          points.push_back(b);
          break;
        default:
          points.push_back(a);
      }
    }
    seen.insert(seen.end(), points.begin(), points.begin() + 200);
    std::vector<float> intensities(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) intensities[i] = static_cast<float>(i % 97);
    batch.insert(points, intensities, {});
    for (std::size_t i = 0; i < points.size(); ++i) single.insert(points[i], intensities[i]);
    ASSERT_EQ(batch.size(), single.size()) << "scan " << scan;
  }
  const auto a = batch.points();
  const auto b = single.points();
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].count, b[i].count) << "voxel " << i;
    ASSERT_EQ(a[i].position, b[i].position) << "voxel " << i;
    ASSERT_EQ(a[i].intensity, b[i].intensity) << "voxel " << i;
  }
}

// Two voxels whose keys share the slot fingerprint (the top 32 bits of the key's Fibonacci hash,
// as static_map.cpp computes it), so the second one's home slot names the first: the batch
// insert must still tell them apart by the key.
TEST(StaticMapKeys, BatchInsertTellsVoxelsWithOneFingerprintApart) {
  const auto pack = [](std::int64_t x, std::int64_t y, std::int64_t z) {
    constexpr std::int64_t kOffset = std::int64_t{1} << 20;
    return (static_cast<std::uint64_t>(x + kOffset) << 42) |
           (static_cast<std::uint64_t>(y + kOffset) << 21) |
           static_cast<std::uint64_t>(z + kOffset);
  };
  const auto fingerprint = [](std::uint64_t key) {
    return static_cast<std::uint32_t>((key * 0x9E3779B97F4A7C15ull) >> 32);
  };
  // Birthday search among random voxels for two with one fingerprint.
  std::mt19937_64 rng(17);
  std::uniform_int_distribution<std::int64_t> index(-1000, 999);
  std::unordered_map<std::uint32_t, std::array<std::int64_t, 3>> by_fp;
  std::array<std::int64_t, 3> first{}, second{};
  bool collided = false;
  while (!collided) {
    const std::array<std::int64_t, 3> v{index(rng), index(rng), index(rng)};
    const auto [it, fresh] = by_fp.try_emplace(fingerprint(pack(v[0], v[1], v[2])), v);
    if (!fresh && it->second != v) {
      first = it->second;
      second = v;
      collided = true;
    }
  }
  const auto centre = [](const std::array<std::int64_t, 3>& v) {
    return Eigen::Vector3f((static_cast<float>(v[0]) + 0.5f) * static_cast<float>(kVoxel),
                           (static_cast<float>(v[1]) + 0.5f) * static_cast<float>(kVoxel),
                           (static_cast<float>(v[2]) + 0.5f) * static_cast<float>(kVoxel));
  };
  const Eigen::Vector3f a = centre(first), b = centre(second);
  const std::vector<Eigen::Vector3f> points{a, a, b, a, b, b, a};
  const std::vector<float> intensities(points.size(), 1.0f);
  StaticMap map(kVoxel);
  map.insert(points, intensities, {});
  map.insert(points, intensities, {});
  ASSERT_EQ(map.size(), 2u);
  ASSERT_NE(map.voxel_at(a), nullptr);
  ASSERT_NE(map.voxel_at(b), nullptr);
  EXPECT_EQ(map.voxel_at(a)->count, 8u);
  EXPECT_EQ(map.voxel_at(b)->count, 6u);
}

// key_of() names the voxel a point falls in as the map itself does: two points share a key
// exactly when they share a voxel (std::floor of the scaled coordinates), points the map drops
// have none, and after inserting a point, voxel_at() of any point with its key finds that voxel.
TEST(StaticMapKeys, KeyOfNamesTheVoxelAPointFallsIn) {
  const std::vector<float> coords = awkward_coordinates();
  StaticMap map(kVoxel);
  const auto scaled_floor = [](float c) {
    return std::floor(c * static_cast<float>(1.0 / kVoxel));
  };
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::size_t> pick(0, coords.size() - 1);
  int compared = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const Eigen::Vector3f a(coords[pick(rng)], coords[pick(rng)], coords[pick(rng)]);
    const Eigen::Vector3f b(a.x(), coords[pick(rng)], a.z());
    const auto ka = map.key_of(a);
    const auto kb = map.key_of(b);
    if (!a.allFinite()) {
      EXPECT_FALSE(ka.has_value());
    }
    if (!ka || !kb) continue;
    ++compared;
    EXPECT_EQ(*ka == *kb, scaled_floor(a.y()) == scaled_floor(b.y()))
        << a.transpose() << " / " << b.transpose();
  }
  EXPECT_GT(compared, 1000);
  const Eigen::Vector3f p(0.31f, -0.07f, 1.52f);
  const Eigen::Vector3f same(0.39f, -0.01f, 1.58f);
  const Eigen::Vector3f next(0.41f, -0.01f, 1.58f);
  map.insert(p, 1.0f);
  ASSERT_EQ(map.key_of(p), map.key_of(same));
  ASSERT_NE(map.key_of(p), map.key_of(next));
  EXPECT_NE(map.voxel_at(same), nullptr);
  EXPECT_EQ(map.voxel_at(next), nullptr);
}

}  // namespace
}  // namespace ringtrack::mapping
