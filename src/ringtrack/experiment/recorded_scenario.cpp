#include "ringtrack/experiment/recorded_scenario.hpp"

#include <cmath>

#include "ringtrack/pipeline/deskew.hpp"

namespace ringtrack::experiment {

RecordedScenario::RecordedScenario(const sim::Scenario& scenario, std::uint64_t seed, bool deskew)
    : scenario_(scenario), seed_(seed), deskew_(deskew) {
  sim::Simulator simulator(scenario_, seed_);
  model_ = simulator.model();
  precompute_directions();
  const std::int64_t n = simulator.scan_count();
  scans_.reserve(static_cast<std::size_t>(n));
  sim::SimulatedScan scan;
  for (std::int64_t k = 0; k < n; ++k) {
    simulator.next(scan);
    CompactScan c = compact(scan);
    c.next_pose = simulator.sensor_pose_at(simulator.scan_stamp_ns(k + 1));
    scans_.push_back(std::move(c));
  }
}

void RecordedScenario::precompute_directions() {
  const int rings = model_.rings(), cols = model_.columns();
  core::OrganizedScan grid(rings, cols);
  grid.set_uniform_columns(model_, 0);  // the column azimuths every simulated scan has
  for (int r = 0; r < rings; ++r) {
    const double el = model_.elevation_rad[static_cast<std::size_t>(r)];
    cos_el_.push_back(std::cos(el));
    sin_el_.push_back(std::sin(el));
    for (int c = 0; c < cols; ++c) {
      const double az = grid.column_azimuth_rad[static_cast<std::size_t>(c)] +
                        model_.azimuth_offset_rad[static_cast<std::size_t>(r)];
      cos_az_.push_back(std::cos(az));
      sin_az_.push_back(std::sin(az));
    }
  }
}

Eigen::Vector3f RecordedScenario::point(std::size_t i, double range_m) const {
  const auto ring = i / static_cast<std::size_t>(model_.columns());
  const double horizontal = range_m * cos_el_[ring];
  return {static_cast<float>(horizontal * cos_az_[i]), static_cast<float>(horizontal * sin_az_[i]),
          static_cast<float>(range_m * sin_el_[ring] + model_.vertical_offset_m[ring])};
}

bool RecordedScenario::moving() const {
  return scenario_.sensor.motion != sim::SensorMotion::kStatic;
}

RecordedScenario::CompactScan RecordedScenario::compact(const sim::SimulatedScan& scan) const {
  CompactScan c;
  c.stamp_ns = scan.scan.stamp_ns;
  c.pose = scan.pose;
  c.objects = scan.objects;
  // Out-of-range cells keep their status through a stand-in range that set_range() classifies
  // the same way (their true range is not stored by the scan either).
  const auto too_close = static_cast<float>(model_.min_range_m * 0.5);
  const auto too_far = static_cast<float>(model_.max_range_m * 2.0);
  for (std::size_t i = 0; i < scan.scan.size(); ++i) {
    const core::ReturnStatus s = scan.scan.status(i);
    if (s == core::ReturnStatus::kNoReturn) continue;
    c.cells.push_back(static_cast<std::uint32_t>(i));
    c.range_m.push_back(s == core::ReturnStatus::kValid      ? scan.scan.range_m(i)
                        : s == core::ReturnStatus::kTooClose ? too_close
                                                             : too_far);
    c.intensity.push_back(scan.scan.intensity(i));
    c.labels.push_back(scan.labels[i]);
  }
  return c;
}

std::size_t RecordedScenario::memory_bytes() const {
  std::size_t bytes = scans_.capacity() * sizeof(CompactScan);
  for (const CompactScan& c : scans_) {
    bytes += c.cells.capacity() * sizeof(std::uint32_t) + c.range_m.capacity() * sizeof(float) +
             c.intensity.capacity() * sizeof(float) + c.labels.capacity() * sizeof(std::uint32_t) +
             c.objects.capacity() * sizeof(sim::ObjectTruth);
  }
  return bytes;
}

void RecordedScenario::expand(std::size_t k, sim::SimulatedScan& out,
                              core::Pose& pipeline_pose) const {
  const CompactScan& c = scans_.at(k);
  if (out.scan.rings() != model_.rings() || out.scan.columns() != model_.columns()) {
    out.scan = core::OrganizedScan(model_.rings(), model_.columns());
  } else {
    out.scan.reset();
  }
  out.scan.set_uniform_columns(model_, c.stamp_ns);
  out.labels.assign(out.scan.size(), 0);
  // set_range()'s classification, with the point from the precomputed directions.
  for (std::size_t j = 0; j < c.cells.size(); ++j) {
    const std::size_t i = c.cells[j];
    const int ring = out.scan.ring_of(i), column = out.scan.column_of(i);
    const float range = c.range_m[j];
    if (range < model_.min_range_m) {
      out.scan.set_invalid(ring, column, core::ReturnStatus::kTooClose);
    } else if (range > model_.max_range_m) {
      out.scan.set_invalid(ring, column, core::ReturnStatus::kTooFar);
    } else {
      out.scan.set_return(ring, column, range, c.intensity[j], point(i, range));
    }
    out.labels[i] = c.labels[j];
  }
  out.index = static_cast<std::int64_t>(k);
  out.pose = c.pose;
  out.objects = c.objects;
  pipeline_pose =
      moving() && deskew_ ? pipeline::deskew_scan(out.scan, c.pose, c.next_pose) : c.pose;
}

}  // namespace ringtrack::experiment
