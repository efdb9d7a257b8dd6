#include "ringtrack/detection/completion.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace ringtrack::detection {
namespace {

constexpr std::int32_t kFree = -1;
// The cells a walk step may reach: the adjacent ring, the same column and the ones beside it (a
// tilted or turning sensor's rings are not stacked column by column, and a silhouette's edge
// cell may sit diagonally below the last object cell).
constexpr int kColumnSteps[] = {0, -1, 1};
constexpr int kMoves = 6;  // down through kColumnSteps, then up
// A cell whose column continues downwards at nearly the same height lies on the ground: within
// kFlatRise plus kFlatSlope = tan(3 deg) per metre up to kFlatReach (far apart, the next ring's
// ground hit says little about the slope, and a shin 0.1 m up must not count as flat).
constexpr double kFlatRise = 0.03;
constexpr double kFlatSlope = 0.0524;
constexpr double kFlatReach = 1.0;
// How far past its half width the ground beside an object is probed (m).
constexpr double kBesideMargin = 0.3;

}  // namespace

DetectionCompleter::DetectionCompleter(const core::DetectionConfig& config) : config_(config) {}

const std::vector<core::Detection>& DetectionCompleter::complete(
    const core::OrganizedScan& scan, const core::Pose& sensor_pose,
    const std::vector<core::Detection>& detections) {
  out_ = detections;  // element-wise assignment: the index vectors keep their capacity
  for (auto& d : out_) d.completion.clear();
  if (config_.complete_range_m <= 0.0 || out_.empty()) return out_;
  if (owner_.size() != scan.size()) owner_.assign(scan.size(), kFree);
  rotation_ = sensor_pose.rotation.normalized().toRotationMatrix();
  translation_ = sensor_pose.translation;
  // Every detection's own cells first, so none extends into another's.
  for (std::size_t d = 0; d < out_.size(); ++d) {
    for (const std::uint32_t i : out_[d].indices) owner_[i] = static_cast<std::int32_t>(d);
  }
  for (std::size_t d = 0; d < out_.size(); ++d) {
    extend(scan, static_cast<std::int32_t>(d), out_[d]);
    finish(scan, out_[d]);
  }
  for (const auto& d : out_) {
    for (const std::uint32_t i : d.indices) owner_[i] = kFree;
    for (const std::uint32_t i : d.completion) owner_[i] = kFree;
  }
  return out_;
}

bool DetectionCompleter::level_with(const core::OrganizedScan& scan, std::size_t k,
                                    const Eigen::Vector3d& w) const {
  if (!scan.valid(k)) return false;
  const Eigen::Vector3d step = world(scan, k) - w;
  return std::abs(step.z()) <= kFlatRise + kFlatSlope * std::min(kFlatReach, step.head<2>().norm());
}

bool DetectionCompleter::on_ground(const core::OrganizedScan& scan, std::size_t j,
                                   const Eigen::Vector3d& w, float half_width_m) const {
  const int columns = scan.columns();
  // Below: the column continues at the same height (the next ring hits the ground in front).
  if (j >= static_cast<std::size_t>(columns) && level_with(scan, j - columns, w)) return true;
  // Beside, just past the object's half width: the ring continues at the same height and range
  // (a surface wider than the object: the ground at its feet, which the bottom ring hits with
  // no ring below to tell).
  const float range = scan.range_m(j);
  const double step_rad = 2.0 * std::numbers::pi / columns;
  const int offset = 1 + static_cast<int>(std::ceil((half_width_m + kBesideMargin) /
                                                    (static_cast<double>(range) * step_rad)));
  if (offset >= columns / 2) return false;
  const int ring = scan.ring_of(j);
  const int column = scan.column_of(j);
  for (const int side : {-offset, offset}) {
    const std::size_t k = scan.index(ring, (column + side + columns) % columns);
    if (level_with(scan, k, w) && std::abs(scan.range_m(k) - range) <= config_.complete_range_m) {
      return true;
    }
  }
  return false;
}

void DetectionCompleter::extend(const core::OrganizedScan& scan, std::int32_t owner,
                                core::Detection& detection) {
  const auto columns = static_cast<std::size_t>(scan.columns());
  const std::size_t cells = scan.size();
  const auto margin = static_cast<float>(config_.complete_margin_m);
  const Eigen::Vector3d lo =
      (detection.box.min - Eigen::Vector3f(margin, margin, 0.0f)).cast<double>();
  const Eigen::Vector3d hi = (detection.box.max + Eigen::Vector3f::Constant(margin)).cast<double>();
  const auto tolerance = static_cast<float>(config_.complete_range_m);
  const float half_width = 0.5f * (detection.box.max - detection.box.min).head<2>().norm();
  const float* range = scan.ranges().data();
  const std::size_t own = detection.indices.size();
  // Walks the object's cells, the detector's and then the added ones (the completion grows
  // while it is walked: a cell added below is itself extended further down).
  for (std::size_t k = 0; k < own + detection.completion.size(); ++k) {
    const std::uint32_t i = k < own ? detection.indices[k] : detection.completion[k - own];
    const std::size_t column = i % columns;
    for (int move = 0; move < kMoves; ++move) {
      const bool up = move >= kMoves / 2;
      if (up ? i + columns >= cells : i < columns) continue;
      const std::size_t next_column =
          (column + columns + kColumnSteps[move % (kMoves / 2)]) % columns;
      const std::size_t j = (up ? i + columns : i - columns) - column + next_column;
      if (owner_[j] != kFree || !scan.valid(j)) continue;
      if (std::abs(range[j] - range[i]) > tolerance) continue;
      const Eigen::Vector3d w = world(scan, j);
      if (w.x() < lo.x() || w.x() > hi.x() || w.y() < lo.y() || w.y() > hi.y() || w.z() > hi.z()) {
        continue;
      }
      // A surface the column climbs steeply (legs) continues the object; one it crosses at a
      // shallow angle does not.
      const Eigen::Vector3d step = w - world(scan, i);
      if (std::abs(step.z()) < step.head<2>().norm()) continue;
      if (!up && on_ground(scan, j, w, half_width)) continue;
      owner_[j] = owner;
      detection.completion.push_back(static_cast<std::uint32_t>(j));
    }
  }
}

void DetectionCompleter::finish(const core::OrganizedScan& scan, core::Detection& detection) {
  if (detection.completion.empty()) return;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double low = detection.box.min.z();
  double high = detection.box.max.z();
  for (const std::uint32_t i : detection.completion) {
    const Eigen::Vector3d w = world(scan, i);
    sum += w;
    low = std::min(low, w.z());
    high = std::max(high, w.z());
  }
  // A person completed is still person-sized; a wall edge or a pillar completed runs from the
  // floor up: it keeps no completion.
  if (high - low > config_.max_height_m) {
    for (const std::uint32_t i : detection.completion) owner_[i] = kFree;
    detection.completion.clear();
    return;
  }
  const auto own = static_cast<double>(detection.indices.size());
  const auto added = static_cast<double>(detection.completion.size());
  sum += own * detection.centroid.cast<double>();
  detection.completed_centroid = (sum / (own + added)).cast<float>();
  std::sort(detection.completion.begin(), detection.completion.end());
}

}  // namespace ringtrack::detection
