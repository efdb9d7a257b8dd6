#pragma once
/// Completion of detections along their columns: the object's cells the segmentation missed.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "ringtrack/core/config.hpp"
#include "ringtrack/core/detection.hpp"
#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/pose.hpp"

namespace ringtrack::detection {

/// Finds, for each detection, the cells of the rings above and below its own (same column or one
/// beside it) that hit the same surface, and stores them as its completion
/// (core::Detection::completion, completed_centroid). A cell joins when its range differs by at
/// most complete_range_m from the neighbouring object cell it is reached from, the step between
/// the two is steeper than 45 degrees, it lies within the detection's box grown by
/// complete_margin_m horizontally and not above the box's top by more than that, no other
/// detection has it, and (going down) it is not on the ground: neither the cell below it in the
/// column nor the cells of its ring just past the object's half width on either side continue it
/// at the same height (those beside also at the same range). Repeated ring by ring, so a person's
/// legs join the torso the segmentation found. Why: the segmentation finds an object by the range
/// jumps along each ring, and a low ring that hits the legs where the ground behind is at a
/// similar range has no jump there; those cells stayed unsegmented, the reported centroid sat
/// 0.1-0.3 m too high on people with few points and their legs stayed in the static map
/// (docs/detection.md, "Completion"). A detection that would grow taller than max_height_m gets
/// no completion. Centroid, covariance, box and indices stay as the detector made them.
///
/// Cost: O(cells of the detections); the buffers live in the object, so steady-state calls do
/// not allocate.
class DetectionCompleter {
 public:
  /// Reads complete_range_m, complete_margin_m and max_height_m (validated config).
  explicit DetectionCompleter(const core::DetectionConfig& config);

  /// The detections of `scan` (world frame by `sensor_pose`) with their completions; with
  /// complete_range_m 0 a copy. The returned reference stays valid until the next call.
  const std::vector<core::Detection>& complete(const core::OrganizedScan& scan,
                                               const core::Pose& sensor_pose,
                                               const std::vector<core::Detection>& detections);

 private:
  void extend(const core::OrganizedScan& scan, std::int32_t owner, core::Detection& detection);
  [[nodiscard]] bool level_with(const core::OrganizedScan& scan, std::size_t k,
                                const Eigen::Vector3d& w) const;
  [[nodiscard]] bool on_ground(const core::OrganizedScan& scan, std::size_t j,
                               const Eigen::Vector3d& w, float half_width_m) const;
  void finish(const core::OrganizedScan& scan, core::Detection& detection);
  [[nodiscard]] Eigen::Vector3d world(const core::OrganizedScan& scan, std::size_t i) const {
    return rotation_ * scan.point(i).cast<double>() + translation_;
  }

  core::DetectionConfig config_;
  std::vector<core::Detection> out_;
  std::vector<std::int32_t> owner_;  // per cell: index of the detection holding it, or -1
  Eigen::Matrix3d rotation_{Eigen::Matrix3d::Identity()};  // of the call's sensor pose
  Eigen::Vector3d translation_{Eigen::Vector3d::Zero()};
};

}  // namespace ringtrack::detection
