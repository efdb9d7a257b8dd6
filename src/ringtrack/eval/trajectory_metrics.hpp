#pragma once
/// Accuracy of an estimated sensor trajectory against a reference (docs/evaluation.md,
/// "Trajectories"): absolute trajectory error after a rigid alignment (TUM RGB-D benchmark) and
/// relative translation / rotation error over path segments (KITTI odometry benchmark).

#include <cstdint>
#include <span>
#include <vector>

#include "ringtrack/core/pose.hpp"

namespace ringtrack::eval {

/// How the trajectories are compared.
struct TrajectoryMetricsOptions {
  /// Segment lengths of the relative error (m, along the reference path); KITTI uses 100..800 m.
  std::vector<double> segment_lengths_m{10, 20, 30, 40, 50, 60, 70, 80, 90, 100};
  /// Start a segment at every this many matched poses (KITTI: 10).
  std::size_t segment_step{1};
};

/// The figures.
struct TrajectoryMetrics {
  std::size_t matched_poses{0};  ///< estimated poses inside the reference's time span
  double path_length_m{0.0};     ///< of the reference over the matched poses
  double ate_rmse_m{0.0};        ///< absolute translation error after rigid alignment: RMSE
  double ate_mean_m{0.0};        ///< ... mean
  double ate_max_m{0.0};         ///< ... largest
  std::size_t segments{0};       ///< relative-error segments evaluated (0: path too short)
  double rte_percent{0.0};       ///< mean translation error per segment length, percent
  double rre_deg_per_m{0.0};     ///< mean rotation error per segment length, degrees per metre
  double final_drift_m{0.0};     ///< end-point error after aligning the first poses
};

/// Compares estimate with reference. Each estimated pose is matched with the reference
/// interpolated at its stamp (linear translation, slerp); estimated poses outside the
/// reference's span are left out. Both must be in increasing stamp order. Throws
/// core::InputError when fewer than two poses match or the stamps are out of order.
[[nodiscard]] TrajectoryMetrics trajectory_metrics(std::span<const core::Pose> estimate,
                                                   std::span<const core::Pose> reference,
                                                   const TrajectoryMetricsOptions& options = {});

}  // namespace ringtrack::eval
