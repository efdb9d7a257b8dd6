#include "ringtrack/pipeline/deskew.hpp"

#include <string>

#include "ringtrack/core/error.hpp"

namespace ringtrack::pipeline {

core::Pose interpolate_pose(const core::Pose& start, const core::Pose& end, std::int64_t t_ns) {
  const double u = static_cast<double>(t_ns - start.stamp_ns) /
                   static_cast<double>(end.stamp_ns - start.stamp_ns);
  core::Pose p;
  p.stamp_ns = t_ns;
  p.translation = start.translation + u * (end.translation - start.translation);
  p.rotation = start.rotation.normalized().slerp(u, end.rotation.normalized());
  return p;
}

core::Pose deskew_scan(core::OrganizedScan& scan, const core::Pose& start, const core::Pose& end) {
  if (end.stamp_ns <= start.stamp_ns) {
    throw core::InputError("deskew: the end pose (" + std::to_string(end.stamp_ns) +
                           " ns) must be later than the start pose (" +
                           std::to_string(start.stamp_ns) + " ns)");
  }
  core::Pose ref = interpolate_pose(start, end, scan.stamp_ns);  // not const, so it is moved out
  const Eigen::Isometry3d ref_from_world = ref.isometry().inverse();
  const int columns = scan.columns();
  const bool stamped = scan.column_stamp_ns.size() == static_cast<std::size_t>(columns);
  if (!stamped) return ref;  // no column times: nothing to compensate
  for (int c = 0; c < columns; ++c) {
    const std::int64_t t = scan.column_stamp_ns[static_cast<std::size_t>(c)];
    if (t == scan.stamp_ns) continue;
    // Column frame -> world -> reference frame; float precision suffices for a 0.1 s motion.
    const Eigen::Isometry3d ref_from_column =
        ref_from_world * interpolate_pose(start, end, t).isometry();
    const Eigen::Matrix3f rotation = ref_from_column.linear().cast<float>();
    const Eigen::Vector3f translation = ref_from_column.translation().cast<float>();
    for (int r = 0; r < scan.rings(); ++r) {
      const std::size_t i = scan.index(r, c);
      if (!scan.valid(i)) continue;
      scan.set_return(r, c, scan.range_m(i), scan.intensity(i),
                      rotation * scan.point(i) + translation);
    }
  }
  return ref;
}

}  // namespace ringtrack::pipeline
