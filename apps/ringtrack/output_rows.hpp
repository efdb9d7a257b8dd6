#pragma once
// Conversions from pipeline and simulator results to the rows of tracks.csv and objects.csv,
// shared by run, simulate and benchmark so the files they write cannot drift apart.

#include <cstdint>

#include "ringtrack/io/csv_writers.hpp"
#include "ringtrack/sim/simulator.hpp"
#include "ringtrack/tracking/tracker.hpp"

namespace ringtrack::cli {

/// One tracks.csv row: a hypothesis after the update of scan `scan`, moved from the pipeline's
/// local frame to the world frame by origin (pipeline::Pipeline::origin()).
inline io::TrackRow track_row(std::uint64_t scan, std::int64_t stamp_ns,
                              const tracking::Hypothesis& h, const Eigen::Vector3d& origin) {
  io::TrackRow row;
  row.scan = scan;
  row.stamp_ns = stamp_ns;
  row.id = h.id;
  row.position = h.reported_position + origin;
  row.velocity = h.velocity_mps;
  row.box = core::Box3d::shifted(h.box, origin);
  row.dynamic = h.dynamic;
  row.ever_dynamic = h.ever_dynamic;
  row.age = static_cast<std::uint32_t>(h.age_scans);
  row.points = static_cast<std::uint32_t>(h.points);
  row.person = h.person;
  return row;
}

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
