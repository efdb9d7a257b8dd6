#include "support/naive_detection.hpp"

#include <Eigen/Eigenvalues>
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

// One cluster's cells with their world points.
struct Part {
  std::vector<std::uint32_t> cells;
  std::vector<Eigen::Vector3d> world;
};

// The split step as documented: the coverage profile of the points along the principal
// horizontal axis, cut in the middle of the deepest valley window, recursively.
void split_part(const Part& part, int depth, const core::DetectionConfig& config,
                const Eigen::Vector3d& sensor, double azimuth_step_rad, std::vector<Part>& out) {
  const std::size_t n = part.cells.size();
  if (config.split_min_width_m <= 0.0 || depth >= detection::kMaxSplitDepth || n < 2) {
    out.push_back(part);
    return;
  }
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& w : part.world) mean += w.head<2>();
  mean /= static_cast<double>(n);
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const auto& w : part.world) {
    const Eigen::Vector2d d = w.head<2>() - mean;
    cov += d * d.transpose();
  }
  // Eigenvector of the larger eigenvalue (the solver sorts them ascending), pointing to +x.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(cov);
  Eigen::Vector2d axis = solver.eigenvectors().col(1);
  if (axis.x() < 0.0 || (axis.x() == 0.0 && axis.y() < 0.0)) axis = -axis;

  std::vector<double> position;
  for (const auto& w : part.world) position.push_back(axis.dot(w.head<2>() - mean));
  double lo = 1e300, hi = -1e300;
  for (const double p : position) {
    lo = std::min(lo, p);
    hi = std::max(hi, p);
  }
  if (hi - lo <= config.split_min_width_m) {
    out.push_back(part);
    return;
  }
  // Only axes within 60 degrees of the tangential direction at the centroid.
  {
    const Eigen::Vector2d c = mean - sensor.head<2>();
    const Eigen::Vector2d tangent(-c.y(), c.x());
    if (!(std::abs(axis.dot(tangent)) >= detection::kSplitMinAxisCos * c.norm())) {
      out.push_back(part);
      return;
    }
  }
  // Coverage: point k stands for the interval of its footprint (horizontal distance * azimuth
  // step / |cos| of the angle between axis and tangential direction, |cos| >= 0.25) around its
  // position, with unit mass spread evenly. A window's mass is the mass of all points inside it.
  const double bin = config.split_bin_m;
  const double sub = bin / static_cast<double>(detection::kSubBins);
  const int sub_bins = static_cast<int>(std::floor((hi - lo) / sub)) + 1;
  const int per_window = static_cast<int>(detection::kSubBins);
  std::vector<double> from(n), to(n);
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector2d d = part.world[k].head<2>() - sensor.head<2>();
    const double h = d.norm();
    double footprint = 0.0;
    if (h > 0.0) {
      const Eigen::Vector2d tangent(-d.y() / h, d.x() / h);
      footprint = h * azimuth_step_rad / std::max(std::abs(axis.dot(tangent)), 0.25);
    }
    from[k] = position[k] - 0.5 * footprint;
    to[k] = position[k] + 0.5 * footprint;
  }
  // The profile covers [lo, lo + sub_bins * sub); mass outside it is lost.
  const double end = lo + sub_bins * sub;
  auto window_mass = [&](int j) {
    const double a = lo + j * sub, b = lo + (j + per_window) * sub;
    double mass = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      if (to[k] - from[k] <= 2e-9 * sub) {  // no footprint: a point mass in its sub-bin
        const int s =
            std::min(static_cast<int>(std::floor((position[k] - lo) / sub)), sub_bins - 1);
        if (s >= j && s < j + per_window) mass += 1.0;
        continue;
      }
      const double x0 = std::max({from[k], a, lo}), x1 = std::min({to[k], b, end});
      if (x1 > x0) mass += (x1 - x0) / (to[k] - from[k]);
    }
    return mass;
  };
  const int windows = sub_bins - per_window + 1;
  std::vector<double> mass(static_cast<std::size_t>(std::max(windows, 0)));
  for (int j = 0; j < windows; ++j) mass[static_cast<std::size_t>(j)] = window_mass(j);
  // Every window with a whole window left and right of it is a candidate valley; its peak is
  // the smaller of the highest such windows on its two sides. Keep the smallest mass / peak,
  // the first on ties (within 1e-9).
  int best = -1;
  double best_score = 2.0;
  if (sub_bins >= 3 * per_window) {
    for (int j = per_window; j + per_window < windows; ++j) {
      double left = 0, right = 0;
      for (int q = 0; q <= j - per_window; ++q)
        left = std::max(left, mass[static_cast<std::size_t>(q)]);
      for (int q = j + per_window; q < windows; ++q) {
        right = std::max(right, mass[static_cast<std::size_t>(q)]);
      }
      const double peak = std::min(left, right);
      const double c = mass[static_cast<std::size_t>(j)];
      if (!(c < peak) || c > config.split_valley_ratio * peak) continue;
      const double score = c / peak;
      if (score < best_score - 1e-9) {
        best = j;
        best_score = score;
      }
    }
  }
  if (best < 0) {
    out.push_back(part);
    return;
  }
  const double cut = lo + (best + 0.5 * per_window) * sub;
  Part left, right;
  for (std::size_t k = 0; k < n; ++k) {
    Part& side = position[k] < cut ? left : right;
    side.cells.push_back(part.cells[k]);
    side.world.push_back(part.world[k]);
  }
  // Both parts must have min_cluster_points points, else the cluster stays whole.
  const auto min_points = static_cast<std::size_t>(config.min_cluster_points);
  if (left.cells.size() < min_points || right.cells.size() < min_points) {
    out.push_back(part);
    return;
  }
  split_part(left, depth + 1, config, sensor, azimuth_step_rad, out);
  split_part(right, depth + 1, config, sensor, azimuth_step_rad, out);
}

}  // namespace

std::vector<core::Detection> naive_detect(const core::OrganizedScan& scan,
                                          const std::vector<std::uint8_t>& labels,
                                          const core::DetectionConfig& config,
                                          const core::Pose& pose,
                                          const std::vector<Eigen::Vector3f>& predictions,
                                          const core::SceneMemory* memory) {
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
  const double azimuth_step_rad = 2.0 * std::numbers::pi / scan.columns();
  std::vector<Part> parts;
  for (auto& [root, cells] : components) {
    Part whole;
    whole.cells = cells;
    for (const auto i : cells) whole.world.push_back(world_T_sensor * scan.point(i).cast<double>());
    split_part(whole, 0, config, pose.translation, azimuth_step_rad, parts);
  }

  std::vector<core::Detection> out;
  for (auto& [cells, world] : parts) {
    // Below min_cluster_points a cluster is sparse when every point stands where the memory saw
    // free space (then the strict model judges it), else it can only be relaxed, from
    // relaxed_min_cluster_points points.
    const bool small = cells.size() < static_cast<std::size_t>(config.min_cluster_points);
    bool sparse = small && memory != nullptr &&
                  cells.size() >= static_cast<std::size_t>(config.sparse_min_points);
    for (std::size_t k = 0; k < cells.size() && sparse; ++k) {
      sparse = memory->seen_free_before(scan, cells[k], world[k], config.background_margin_m);
    }
    if (small && !sparse &&
        cells.size() < static_cast<std::size_t>(config.relaxed_min_cluster_points)) {
      continue;
    }
    bool edge_ring = false;
    double range_sum = 0;
    for (const auto i : cells) {
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
    const bool strict = (!small || sparse) && min_z <= config.max_altitude_m &&
                        height <= config.max_height_m && diagonal <= config.max_diagonal_m &&
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
    d.sparse = sparse && strict;
    out.push_back(std::move(d));
  }
  std::sort(out.begin(), out.end(), [](const core::Detection& a, const core::Detection& b) {
    return a.indices.front() < b.indices.front();
  });
  return out;
}

}  // namespace ringtrack::testing
