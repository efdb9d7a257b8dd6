#include "support/naive_detection.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <numbers>
#include <numeric>

namespace ringtrack::testing {
namespace {

int find_root(std::vector<int>& parent, int a) {
  while (parent[static_cast<std::size_t>(a)] != a) a = parent[static_cast<std::size_t>(a)];
  return a;
}

bool linked(const core::OrganizedScan& scan, const core::DetectionConfig& config, std::size_t a,
            std::size_t b) {
  const int columns = scan.columns();
  const int d_ring = std::abs(scan.ring_of(a) - scan.ring_of(b));
  int d_column = std::abs(scan.column_of(a) - scan.column_of(b));
  d_column = std::min(d_column, columns - d_column);  // the ring is circular
  if (d_ring + d_column > config.neighbor_radius) return false;
  const auto theta = static_cast<float>(config.join_distance_m);
  if (config.join_rule == core::JoinRule::kEuclidean) {
    const float dx = scan.xs()[a] - scan.xs()[b];
    const float dy = scan.ys()[a] - scan.ys()[b];
    const float dz = scan.zs()[a] - scan.zs()[b];
    return dx * dx + dy * dy + dz * dz < theta * theta;
  }
  return std::abs(scan.range_m(a) - scan.range_m(b)) < theta;
}

}  // namespace

std::vector<core::Detection> naive_detect(const core::OrganizedScan& scan,
                                          const std::vector<std::uint8_t>& labels,
                                          const core::DetectionConfig& config,
                                          const core::Pose& pose,
                                          const std::vector<Eigen::Vector3f>& predictions) {
  std::vector<std::size_t> points;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (labels[i] == 1 && scan.valid(i)) points.push_back(i);
  }
  std::vector<int> parent(points.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (std::size_t a = 0; a < points.size(); ++a) {
    for (std::size_t b = a + 1; b < points.size(); ++b) {
      if (!linked(scan, config, points[a], points[b])) continue;
      const int ra = find_root(parent, static_cast<int>(a));
      const int rb = find_root(parent, static_cast<int>(b));
      if (ra != rb) parent[static_cast<std::size_t>(std::max(ra, rb))] = std::min(ra, rb);
    }
  }
  // Components keyed by their root (the smallest member, as roots are the smaller index).
  std::map<int, std::vector<std::uint32_t>> components;
  for (std::size_t a = 0; a < points.size(); ++a) {
    components[find_root(parent, static_cast<int>(a))].push_back(
        static_cast<std::uint32_t>(points[a]));
  }

  const Eigen::Isometry3d world_T_sensor = pose.isometry();
  std::vector<core::Detection> out;
  for (auto& [root, cells] : components) {
    // Below min_cluster_points a cluster can only be relaxed, from relaxed_min_cluster_points.
    const bool small = cells.size() < static_cast<std::size_t>(config.min_cluster_points);
    if (small && cells.size() < static_cast<std::size_t>(config.relaxed_min_cluster_points)) {
      continue;
    }
    std::vector<Eigen::Vector3d> world;
    bool edge_ring = false;
    double range_sum = 0;
    for (const auto i : cells) {
      world.push_back(world_T_sensor * scan.point(i).cast<double>());
      edge_ring = edge_ring || scan.ring_of(i) == 0 || scan.ring_of(i) == scan.rings() - 1;
      range_sum += scan.range_m(i);
    }
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    double min_x = 1e300, max_x = -1e300, min_y = 1e300, max_y = -1e300, min_z = 1e300,
           max_z = -1e300;
    for (const auto& w : world) {
      mean += w;
      min_x = std::min(min_x, w.x());
      max_x = std::max(max_x, w.x());
      min_y = std::min(min_y, w.y());
      max_y = std::max(max_y, w.y());
      min_z = std::min(min_z, w.z());
      max_z = std::max(max_z, w.z());
    }
    const auto n = static_cast<double>(world.size());
    mean /= n;
    const double height = max_z - min_z;
    const double diagonal =
        std::sqrt((max_x - min_x) * (max_x - min_x) + (max_y - min_y) * (max_y - min_y));
    const double gap =
        range_sum / n * std::tan(config.min_height_ring_gap_deg * std::numbers::pi / 180.0);
    const bool strict = !small && min_z <= config.max_altitude_m && height <= config.max_height_m &&
                        diagonal <= config.max_diagonal_m &&
                        (edge_ring || height + gap >= config.min_height_m);
    bool near = false;
    for (const auto& p : predictions) {
      const double dx = p.x() - mean.x(), dy = p.y() - mean.y();
      near = near || std::sqrt(dx * dx + dy * dy) <= config.relaxed_radius_m;
    }
    const bool relaxed_ok = near && min_z <= config.max_altitude_m &&
                            height <= config.max_height_m &&
                            diagonal <= config.relaxed_max_diagonal_m;
    if (!strict && !relaxed_ok) continue;

    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const auto& w : world) cov += (w - mean) * (w - mean).transpose();
    cov /= n;
    for (int k = 0; k < 3; ++k) {
      cov(k, k) = std::max(cov(k, k), config.min_position_stddev_m * config.min_position_stddev_m);
    }
    core::Detection d;
    d.centroid = mean.cast<float>();
    d.covariance = cov.cast<float>();
    d.box.min = Eigen::Vector3d(min_x, min_y, min_z).cast<float>();
    d.box.max = Eigen::Vector3d(max_x, max_y, max_z).cast<float>();
    std::sort(cells.begin(), cells.end());
    d.indices = cells;
    d.relaxed = !strict;
    out.push_back(std::move(d));
  }
  return out;
}

}  // namespace ringtrack::testing
