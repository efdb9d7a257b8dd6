// Trajectory metrics against hand-computed values.

#include "ringtrack/eval/trajectory_metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "ringtrack/core/error.hpp"

namespace ringtrack {
namespace {

core::Pose pose_at(double t_s, const Eigen::Vector3d& xyz,
                   const Eigen::Quaterniond& q = Eigen::Quaterniond::Identity()) {
  core::Pose p;
  p.stamp_ns = static_cast<std::int64_t>(std::llround(t_s * 1e9));
  p.translation = xyz;
  p.rotation = q;
  return p;
}

// Reference: straight along x at 1 m/s for 20 s, a pose a second.
std::vector<core::Pose> straight_line() {
  std::vector<core::Pose> out;
  for (int k = 0; k <= 20; ++k) out.push_back(pose_at(k, {static_cast<double>(k), 0, 0}));
  return out;
}

TEST(TrajectoryMetrics, RigidlyMovedCopyHasNoError) {
  const auto ref = straight_line();
  std::vector<core::Pose> est;
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, 0.3, 1).normalized()));
  for (const auto& p : ref) {
    est.push_back(pose_at(1e-9 * static_cast<double>(p.stamp_ns),
                          q * p.translation + Eigen::Vector3d(5, -3, 2), q * p.rotation));
  }
  const auto m = eval::trajectory_metrics(est, ref);
  EXPECT_EQ(m.matched_poses, 21U);
  EXPECT_NEAR(m.ate_rmse_m, 0.0, 1e-9);
  EXPECT_NEAR(m.rte_percent, 0.0, 1e-9);
  EXPECT_NEAR(m.rre_deg_per_m, 0.0, 1e-9);
  EXPECT_NEAR(m.final_drift_m, 0.0, 1e-9);
  EXPECT_NEAR(m.path_length_m, 20.0, 1e-12);
}

// An estimate 1 % too long: every segment is off by 1 % of its length; after the best rigid
// alignment (a shift to the mean) the errors are 0.01 (x - 10) for x = 0..20, whose RMSE is
// 0.01 * sqrt((21^2 - 1) / 12) = 0.0605530 m; the end drifts by 0.2 m.
TEST(TrajectoryMetrics, OnePercentScaleErrorGivesHandComputedFigures) {
  const auto ref = straight_line();
  std::vector<core::Pose> est;
  for (const auto& p : ref) {
    est.push_back(pose_at(1e-9 * static_cast<double>(p.stamp_ns), 1.01 * p.translation));
  }
  eval::TrajectoryMetricsOptions options;
  options.segment_lengths_m = {5, 10};
  const auto m = eval::trajectory_metrics(est, ref, options);
  EXPECT_NEAR(m.ate_rmse_m, 0.01 * std::sqrt(440.0 / 12.0), 1e-9);
  EXPECT_NEAR(m.ate_max_m, 0.1, 1e-9);
  EXPECT_NEAR(m.rte_percent, 1.0, 1e-9);
  EXPECT_EQ(m.segments, 16U + 11U);  // starts 0..15 reach 5 m, 0..10 reach 10 m
  EXPECT_NEAR(m.final_drift_m, 0.2, 1e-9);
}

// A reference sampled every 10 s matches an estimate sampled every 0.5 s along the same line.
TEST(TrajectoryMetrics, InterpolatesTheReferenceAtTheEstimatedStamps) {
  std::vector<core::Pose> ref = {pose_at(0, {0, 0, 0}), pose_at(10, {10, 0, 0})};
  std::vector<core::Pose> est;
  for (int k = 0; k <= 20; ++k) est.push_back(pose_at(0.5 * k, {0.5 * k, 0, 0}));
  eval::TrajectoryMetricsOptions options;
  options.segment_lengths_m = {2};
  const auto m = eval::trajectory_metrics(est, ref, options);
  EXPECT_EQ(m.matched_poses, 21U);
  EXPECT_NEAR(m.ate_rmse_m, 0.0, 1e-9);
  EXPECT_EQ(m.segments, 17U);
}

TEST(TrajectoryMetrics, TooFewMatchesOrUnorderedStampsThrow) {
  const auto ref = straight_line();
  std::vector<core::Pose> late = {pose_at(30, {0, 0, 0}), pose_at(31, {1, 0, 0})};
  EXPECT_THROW((void)eval::trajectory_metrics(late, ref), core::InputError);
  std::vector<core::Pose> unordered = {pose_at(2, {0, 0, 0}), pose_at(1, {1, 0, 0})};
  EXPECT_THROW((void)eval::trajectory_metrics(unordered, ref), core::InputError);
}

}  // namespace
}  // namespace ringtrack
