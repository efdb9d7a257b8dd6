#include "ringtrack/odometry/registration.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

namespace ringtrack::odometry {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

// Adds one weighted correspondence to the normal equations. The rotation's lever arm is taken from
// the sensor position (not the world origin) so that the system stays well conditioned far away.
void accumulate(const Eigen::Vector3d& lever, const Eigen::Vector3d& residual, double w,
                Matrix6d& h, Vector6d& g) {
  Eigen::Matrix<double, 3, 6> j;
  j.leftCols<3>().setIdentity();
  j.rightCols<3>() << 0, lever.z(), -lever.y(), -lever.z(), 0, lever.x(), lever.y(), -lever.x(), 0;
  h.noalias() += w * j.transpose() * j;
  g.noalias() += w * j.transpose() * residual;
}

// The same for a residual along the normal n (1 x 6 Jacobian [n, lever x n]), lower triangle of
// h only: column b from row b down, each entry (w j_a) j_b as Eigen's outer product of (w j) and
// j forms it (bit for bit the same sums), in column segments that SSE2 takes two at a time.
// Always inlined: GCC left it a call per pair otherwise (callgrind).
[[gnu::always_inline]] inline void accumulate_plane(const Eigen::Vector3d& lever,
                                                    const Eigen::Vector3d& n, double residual,
                                                    double w, Matrix6d& h, Vector6d& g) {
  Vector6d j;
  j.head<3>() = n;
  j.tail<3>() = lever.cross(n);
  const Vector6d wj = w * j;
  h.col(0) += j(0) * wj;
  h.col(1).tail<5>() += j(1) * wj.tail<5>();
  h.col(2).tail<4>() += j(2) * wj.tail<4>();
  h.col(3).tail<3>() += j(3) * wj.tail<3>();
  h.col(4).tail<2>() += j(4) * wj.tail<2>();
  h(5, 5) += j(5) * wj(5);
  g.noalias() += (w * residual) * j;
}

}  // namespace

void accumulate_point_to_plane(const Eigen::Vector3d& lever, const Eigen::Vector3d& n,
                               double residual, double w, Matrix6d& h, Vector6d& g) {
  accumulate_plane(lever, n, residual, w, h, g);
}

double geman_mcclure_weight(double residual_m, double scale_m) {
  const double s2 = scale_m * scale_m;
  const double d = s2 + residual_m * residual_m;
  return s2 * s2 / (d * d);
}

Eigen::Matrix3d rotation_from_vector(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle < 1e-12) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

IcpResult register_points(const std::vector<Eigen::Vector3f>& sensor_points, const VoxelMap& map,
                          const Eigen::Isometry3d& initial, const IcpSettings& settings,
                          const std::vector<Eigen::Vector3f>& normals, NeighbourCache* neighbours) {
  const bool plane = settings.point_to_plane && normals.size() == sensor_points.size();
  IcpResult result;
  result.world_T_sensor = initial;
  std::optional<NeighbourCache> own;
  if (neighbours == nullptr || neighbours->size() != sensor_points.size() ||
      neighbours->max_distance_m() != settings.max_distance_m) {
    neighbours = &own.emplace(map, settings.max_distance_m, sensor_points.size());
  }
  Eigen::Vector3f nearest = Eigen::Vector3f::Zero();
  Vector6d previous = Vector6d::Zero();
  for (int it = 0; it < settings.max_iterations; ++it) {
    const Eigen::Matrix3d rotation = result.world_T_sensor.linear();
    const Eigen::Vector3d origin = result.world_T_sensor.translation();
    Matrix6d h = Matrix6d::Zero();
    Vector6d g = Vector6d::Zero();
    std::size_t pairs = 0;
    for (std::size_t i = 0; i < sensor_points.size(); ++i) {
      if (plane && normals[i].isZero()) continue;
      const Eigen::Vector3d lever = rotation * sensor_points[i].cast<double>();
      const Eigen::Vector3d q = lever + origin;
      if (!neighbours->nearest(i, q.cast<float>(), nearest)) continue;
      const Eigen::Vector3d residual = q - nearest.cast<double>();
      if (plane) {
        const Eigen::Vector3d n = rotation * normals[i].cast<double>();
        const double e = n.dot(residual);
        accumulate_plane(lever, n, e, geman_mcclure_weight(e, settings.kernel_scale_m), h, g);
      } else {
        accumulate(lever, residual, geman_mcclure_weight(residual.norm(), settings.kernel_scale_m),
                   h, g);
      }
      ++pairs;
    }
    result.iterations = it + 1;
    result.correspondences = pairs;
    if (pairs < 6) break;  // too few pairs to fix six degrees of freedom
    // Point-to-plane pairs filled the lower triangle only; LDLT reads no more, the mirror keeps
    // h whole for readers.
    if (plane) h.triangularView<Eigen::StrictlyUpper>() = h.transpose();
    // Damping of 1 % of each block's mean curvature: a direction the scene does not constrain
    // (along a plain, along a corridor) keeps its prediction instead of taking a step driven by
    // noise; constrained directions only converge a little slower (same solution).
    const double damp_t = 0.01 * h.topLeftCorner<3, 3>().trace() / 3.0 + 1e-9;
    const double damp_r = 0.01 * h.bottomRightCorner<3, 3>().trace() / 3.0 + 1e-9;
    h.diagonal() += (Vector6d() << damp_t, damp_t, damp_t, damp_r, damp_r, damp_r).finished();
    const Vector6d step = h.ldlt().solve(-g);
    if (!step.allFinite()) break;
    result.world_T_sensor.linear() = rotation_from_vector(step.tail<3>()) * rotation;
    result.world_T_sensor.translation() = origin + step.head<3>();
    // Converged; or nearly, and bouncing between two sets of nearest neighbours (the step
    // reverses the previous one).
    const bool bouncing = step.norm() < 10.0 * settings.convergence && step.dot(previous) < 0;
    previous = step;
    if (step.norm() < settings.convergence || bouncing) {
      result.converged = true;
      break;
    }
  }
  return result;
}

double weakest_translation_share(const std::vector<Eigen::Vector3f>& normals) {
  if (normals.empty()) return 0.0;
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& n : normals)
    scatter.noalias() += (n.cast<double>() * n.cast<double>().transpose());
  scatter /= static_cast<double>(normals.size());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(scatter, Eigen::EigenvaluesOnly);
  return std::max(0.0, solver.eigenvalues()(0));
}

}  // namespace ringtrack::odometry
