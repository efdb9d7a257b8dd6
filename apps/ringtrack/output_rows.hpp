#pragma once
// The simulator's ground truth as rows of objects.csv (simulate); tracks.csv's rows are
// runner::track_row's (ringtrack/runner/run.hpp).

#include <cstdint>

#include "ringtrack/io/csv_writers.hpp"
#include "ringtrack/sim/simulator.hpp"

namespace ringtrack::cli {

/// One objects.csv row: the simulator's ground truth of an object in scan `scan`.
inline io::ObjectRow object_row(std::uint64_t scan, std::int64_t stamp_ns,
                                const sim::ObjectTruth& t) {
  io::ObjectRow row;
  row.scan = scan;
  row.stamp_ns = stamp_ns;
  row.id = t.id;
  row.class_name = std::string(sim::class_name(t.object_class));
  row.points = static_cast<std::uint32_t>(t.hit_points);
  row.centroid = t.centroid_m.cast<double>();
  row.box = core::Box3d::shifted(t.box, Eigen::Vector3d::Zero());
  row.true_center = t.body_center_m.cast<double>();
  row.moving = t.moving;
  return row;
}

}  // namespace ringtrack::cli
