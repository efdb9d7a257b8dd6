#pragma once
// Reference detection: the definition of region growing and the object model, computed the slow
// obvious way (union-find over every pair of segment points, then the model per component).

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "ringtrack/core/config.hpp"
#include "ringtrack/core/detection.hpp"
#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/pose.hpp"
#include "ringtrack/core/scene_memory.hpp"
#include "ringtrack/detection/detector.hpp"

namespace ringtrack::testing {

/// Detections as paper III.C defines them: two segment points (label 1, valid) are linked when
/// their grid distance |d_ring| + circular |d_column| is at most neighbor_radius and the join
/// rule holds; clusters are the connected components; each is split at density valleys along
/// its principal horizontal axis while wider than split_min_width_m (up to
/// detection::kMaxSplitDepth levels); the object model then filters the parts
/// (clusters below min_cluster_points only as relaxed detections, from
/// relaxed_min_cluster_points points, or as sparse detections under the strict model when the
/// memory says every point stands where earlier scans saw free space).
/// Ordered by smallest grid index, indices ascending. O(segment points^2).
std::vector<core::Detection> naive_detect(const core::OrganizedScan& scan,
                                          const std::vector<std::uint8_t>& labels,
                                          const core::DetectionConfig& config,
                                          const core::Pose& pose,
                                          const std::vector<Eigen::Vector3f>& predictions = {},
                                          const core::SceneMemory* memory = nullptr);

}  // namespace ringtrack::testing
