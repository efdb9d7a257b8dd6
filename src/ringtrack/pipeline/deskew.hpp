#pragma once
/// Motion compensation of a scan taken by a moving sensor.

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/pose.hpp"

namespace ringtrack::pipeline {

/// Sensor pose at time t_ns from two poses bracketing a scan: linear translation and slerp
/// between them (extrapolated outside), exact when the sensor moves uniformly.
[[nodiscard]] core::Pose interpolate_pose(const core::Pose& start, const core::Pose& end,
                                          std::int64_t t_ns);

/// Re-expresses every valid point of a scan whose columns were measured from a moving sensor at
/// their own stamps (OrganizedScan::column_stamp_ns) in the sensor frame at scan.stamp_ns. The
/// sensor pose at a column's stamp is interpolated between start and end (sensor in world, with
/// stamps, e.g. this scan's and the next scan's); ranges are kept as measured. Returns the pose
/// at scan.stamp_ns, the pose to give Pipeline::process with the compensated scan. Throws
/// core::InputError when end is not later than start.
core::Pose deskew_scan(core::OrganizedScan& scan, const core::Pose& start, const core::Pose& end);

}  // namespace ringtrack::pipeline
