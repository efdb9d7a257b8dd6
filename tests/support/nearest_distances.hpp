#pragma once
// Nearest-point distances between two point sets by a uniform grid search: an oracle for
// decoder-vs-reference tests that shares nothing with the decoders.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>
#include <vector>

namespace ringtrack::test {

/// For every query point, the distance to the nearest point of `cloud` (infinity when `cloud` is
/// empty) and, when `nearest` is given, that point's index. Cells of `cell_m`; rings of cells are
/// searched outwards until no closer point can exist, so results are exact (the same as a
/// brute-force search).
inline std::vector<double> nearest_distances(const std::vector<Eigen::Vector3d>& cloud,
                                             const std::vector<Eigen::Vector3d>& queries,
                                             double cell_m = 0.1,
                                             std::vector<std::size_t>* nearest = nullptr) {
  std::vector<double> out(queries.size(), std::numeric_limits<double>::infinity());
  if (nearest != nullptr) nearest->assign(queries.size(), 0);
  if (cloud.empty()) return out;
  const auto key = [](std::int64_t x, std::int64_t y, std::int64_t z) {
    return (static_cast<std::uint64_t>(x & 0x1FFFFF) << 42) |
           (static_cast<std::uint64_t>(y & 0x1FFFFF) << 21) |
           static_cast<std::uint64_t>(z & 0x1FFFFF);
  };
  const auto cell = [cell_m](double v) {
    return static_cast<std::int64_t>(std::floor(v / cell_m));
  };
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> grid;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto& p = cloud[i];
    grid[key(cell(p.x()), cell(p.y()), cell(p.z()))].push_back(static_cast<std::uint32_t>(i));
  }
  const int max_ring = 4000;  // 400 m at 0.1 m cells: beyond any test scene
  for (std::size_t q = 0; q < queries.size(); ++q) {
    const auto& p = queries[q];
    const std::int64_t cx = cell(p.x()), cy = cell(p.y()), cz = cell(p.z());
    double best2 = std::numeric_limits<double>::infinity();
    std::size_t best_i = 0;
    for (int ring = 0; ring <= max_ring; ++ring) {
      // Every point in ring k lies at least (k - 1) cells away.
      if (ring > 0) {
        const double reach = (ring - 1) * cell_m;
        if (reach * reach > best2) break;
      }
      for (std::int64_t dx = -ring; dx <= ring; ++dx) {
        for (std::int64_t dy = -ring; dy <= ring; ++dy) {
          const bool edge_xy = std::abs(dx) == ring || std::abs(dy) == ring;
          for (std::int64_t dz = -ring; dz <= ring; ++dz) {
            if (!edge_xy && std::abs(dz) != ring) dz = ring;  // only the ring's shell
            const auto it = grid.find(key(cx + dx, cy + dy, cz + dz));
            if (it == grid.end()) continue;
            for (const std::uint32_t i : it->second) {
              const double d2 = (cloud[i] - p).squaredNorm();
              if (d2 < best2) {
                best2 = d2;
                best_i = i;
              }
            }
          }
        }
      }
    }
    out[q] = std::sqrt(best2);
    if (nearest != nullptr) (*nearest)[q] = best_i;
  }
  return out;
}

/// The q-quantile (0..1) of values (nearest rank on a sorted copy).
inline double quantile(std::vector<double> values, double q) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(values.begin(), values.end());
  const auto i = static_cast<std::size_t>(
      std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1) + 0.5);
  return values[std::min(i, values.size() - 1)];
}

/// Reads the x y z of a binary PCD whose first three fields are float x, y, z (more fields
/// allowed, all 4-byte or with SIZE given); empty on an unexpected layout.
std::vector<Eigen::Vector3d> read_pcd_xyz(const std::string& path);

}  // namespace ringtrack::test
