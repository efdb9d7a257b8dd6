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

}  // namespace
}  // namespace ringtrack::mapping
