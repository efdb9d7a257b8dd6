#include "ringtrack/eval/trajectory_metrics.hpp"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "ringtrack/core/error.hpp"

namespace ringtrack::eval {
namespace {

void check_order(std::span<const core::Pose> poses, const char* what) {
  for (std::size_t i = 1; i < poses.size(); ++i) {
    if (poses[i].stamp_ns <= poses[i - 1].stamp_ns) {
      throw core::InputError(std::string("trajectory metrics: the ") + what + "'s stamps must " +
                             "increase, pose " + std::to_string(i) + " does not");
    }
  }
}

// Pairs of (estimate, reference interpolated at the estimate's stamp).
void match(std::span<const core::Pose> estimate, std::span<const core::Pose> reference,
           std::vector<Eigen::Isometry3d>& est, std::vector<Eigen::Isometry3d>& ref) {
  std::size_t j = 0;
  for (const auto& e : estimate) {
    if (reference.empty() || e.stamp_ns < reference.front().stamp_ns ||
        e.stamp_ns > reference.back().stamp_ns) {
      continue;
    }
    while (j + 1 < reference.size() && reference[j + 1].stamp_ns < e.stamp_ns) ++j;
    core::Pose r = reference[j];
    if (r.stamp_ns != e.stamp_ns && j + 1 < reference.size()) {
      const double u = static_cast<double>(e.stamp_ns - reference[j].stamp_ns) /
                       static_cast<double>(reference[j + 1].stamp_ns - reference[j].stamp_ns);
      r = core::Pose::interpolate(reference[j], reference[j + 1], u);
    }
    est.push_back(e.isometry());
    ref.push_back(r.isometry());
  }
}

// Rigid transform (no scale) that best maps the estimated positions onto the reference ones in
// the least-squares sense (Umeyama 1991, with the reflection fix).
Eigen::Isometry3d align(const std::vector<Eigen::Isometry3d>& est,
                        const std::vector<Eigen::Isometry3d>& ref) {
  Eigen::Vector3d mean_e = Eigen::Vector3d::Zero(), mean_r = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < est.size(); ++i) {
    mean_e += est[i].translation();
    mean_r += ref[i].translation();
  }
  const double n = static_cast<double>(est.size());
  mean_e /= n;
  mean_r /= n;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < est.size(); ++i) {
    cov += (ref[i].translation() - mean_r) * (est[i].translation() - mean_e).transpose();
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d s = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) s(2, 2) = -1;
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = svd.matrixU() * s * svd.matrixV().transpose();
  out.translation() = mean_r - out.linear() * mean_e;
  return out;
}

void absolute_error(const std::vector<Eigen::Isometry3d>& est,
                    const std::vector<Eigen::Isometry3d>& ref, TrajectoryMetrics& m) {
  const Eigen::Isometry3d a = align(est, ref);
  double sum = 0.0, sum2 = 0.0;
  for (std::size_t i = 0; i < est.size(); ++i) {
    const double e = ((a * est[i]).translation() - ref[i].translation()).norm();
    sum += e;
    sum2 += e * e;
    m.ate_max_m = std::max(m.ate_max_m, e);
  }
  const double n = static_cast<double>(est.size());
  m.ate_mean_m = sum / n;
  m.ate_rmse_m = std::sqrt(sum2 / n);
  // End-point drift with the two trajectories tied at their first pose (what a user sees).
  const Eigen::Isometry3d tie = ref.front() * est.front().inverse();
  m.final_drift_m = ((tie * est.back()).translation() - ref.back().translation()).norm();
}

void relative_error(const std::vector<Eigen::Isometry3d>& est,
                    const std::vector<Eigen::Isometry3d>& ref,
                    const TrajectoryMetricsOptions& options, TrajectoryMetrics& m) {
  std::vector<double> distance(ref.size(), 0.0);  // along the reference path
  for (std::size_t i = 1; i < ref.size(); ++i) {
    distance[i] = distance[i - 1] + (ref[i].translation() - ref[i - 1].translation()).norm();
  }
  m.path_length_m = distance.back();
  double t_sum = 0.0, r_sum = 0.0;
  const std::size_t step = std::max<std::size_t>(1, options.segment_step);
  for (std::size_t i = 0; i < ref.size(); i += step) {
    for (const double length : options.segment_lengths_m) {
      const auto end = std::lower_bound(distance.begin() + static_cast<std::ptrdiff_t>(i),
                                        distance.end(), distance[i] + length);
      if (end == distance.end()) continue;
      const auto j = static_cast<std::size_t>(end - distance.begin());
      const Eigen::Isometry3d ref_motion = ref[i].inverse() * ref[j];
      const Eigen::Isometry3d est_motion = est[i].inverse() * est[j];
      const Eigen::Isometry3d error = ref_motion.inverse() * est_motion;
      t_sum += error.translation().norm() / length;
      r_sum += Eigen::AngleAxisd(error.linear()).angle() * 180.0 / std::numbers::pi / length;
      ++m.segments;
    }
  }
  if (m.segments > 0) {
    m.rte_percent = 100.0 * t_sum / static_cast<double>(m.segments);
    m.rre_deg_per_m = r_sum / static_cast<double>(m.segments);
  }
}

}  // namespace

TrajectoryMetrics trajectory_metrics(std::span<const core::Pose> estimate,
                                     std::span<const core::Pose> reference,
                                     const TrajectoryMetricsOptions& options) {
  check_order(estimate, "estimate");
  check_order(reference, "reference");
  std::vector<Eigen::Isometry3d> est, ref;
  match(estimate, reference, est, ref);
  if (est.size() < 2) {
    throw core::InputError("trajectory metrics: " + std::to_string(est.size()) +
                           " estimated poses lie within the reference's time span, need 2");
  }
  TrajectoryMetrics m;
  m.matched_poses = est.size();
  absolute_error(est, ref, m);
  relative_error(est, ref, options, m);
  return m;
}

}  // namespace ringtrack::eval
