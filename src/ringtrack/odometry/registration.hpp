#pragma once
/// Point-to-point ICP of a scan against the local map with a robust (Geman-McClure) kernel, and
/// the degeneracy measure of a scan's geometry.

#include <Eigen/Geometry>
#include <vector>

#include "ringtrack/odometry/voxel_map.hpp"

namespace ringtrack::odometry {

/// Settings of one registration.
struct IcpSettings {
  double max_distance_m{1.0};  ///< correspondences farther apart are dropped
  double kernel_scale_m{0.3};  ///< Geman-McClure scale: residuals of this size weigh 1/4
  int max_iterations{30};
  double convergence{1e-4};    ///< stop when a step moves less (m and rad)
  bool point_to_plane{false};  ///< residual along the point's normal (points without one skipped)
};

/// What one registration found.
struct IcpResult {
  Eigen::Isometry3d world_T_sensor{Eigen::Isometry3d::Identity()};
  int iterations{0};
  std::size_t correspondences{0};  ///< in the last iteration
  bool converged{false};
};

/// Adds one weighted point-to-plane pair to the normal equations: w j j^T to the **lower
/// triangle** of h (the upper one is left alone) and w residual j to g, with the 1 x 6 Jacobian
/// j = [n, lever x n]. Each entry is the one the full outer product h += w j j^T forms (tests
/// compare them bit for bit): 21 products per pair instead of 36.
void accumulate_point_to_plane(const Eigen::Vector3d& lever, const Eigen::Vector3d& n,
                               double residual, double w, Eigen::Matrix<double, 6, 6>& h,
                               Eigen::Matrix<double, 6, 1>& g);

/// Geman-McClure weight of a residual: 1 at 0, 1/4 at the scale, falling as 1/r^4 beyond.
[[nodiscard]] double geman_mcclure_weight(double residual_m, double scale_m);

/// Rotation by the rotation vector w (angle |w| about w / |w|).
[[nodiscard]] Eigen::Matrix3d rotation_from_vector(const Eigen::Vector3d& w);

/// Aligns sensor-frame points to the map, starting from initial (world_T_sensor), by Gauss-Newton
/// on the robustly weighted distances to each point's nearest map point: the whole distance, or
/// (settings.point_to_plane) its component along the point's unit normal in `normals` (sensor
/// frame, same order; a zero normal leaves the point out). `neighbours`, when given, is reused
/// (it must be for this map, the settings' distance and one slot per point; else a fresh one is
/// used): registrations of the same points against the same map in a row search less.
[[nodiscard]] IcpResult register_points(const std::vector<Eigen::Vector3f>& sensor_points,
                                        const VoxelMap& map, const Eigen::Isometry3d& initial,
                                        const IcpSettings& settings,
                                        const std::vector<Eigen::Vector3f>& normals = {},
                                        NeighbourCache* neighbours = nullptr);

/// Smallest eigenvalue of the mean of n n^T over unit normals: the share of the surface
/// orientations that constrains the weakest translation direction (0 on a plane, 1/3 at most).
/// Returns 0 for no normals.
[[nodiscard]] double weakest_translation_share(const std::vector<Eigen::Vector3f>& normals);

}  // namespace ringtrack::odometry
