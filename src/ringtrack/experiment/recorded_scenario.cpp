#include "ringtrack/experiment/recorded_scenario.hpp"

#include "ringtrack/pipeline/deskew.hpp"

namespace ringtrack::experiment {

RecordedScenario::RecordedScenario(const sim::Scenario& scenario, std::uint64_t seed, bool deskew)
    : scenario_(scenario), seed_(seed), deskew_(deskew) {
  sim::Simulator simulator(scenario_, seed_);
  model_ = simulator.model();
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
  for (std::size_t j = 0; j < c.cells.size(); ++j) {
    const std::size_t i = c.cells[j];
    out.scan.set_range(model_, out.scan.ring_of(i), out.scan.column_of(i), c.range_m[j],
                       c.intensity[j]);
    out.labels[i] = c.labels[j];
  }
  out.index = static_cast<std::int64_t>(k);
  out.pose = c.pose;
  out.objects = c.objects;
  pipeline_pose = moving() && deskew_ ? pipeline::deskew_scan(out.scan, c.pose, c.next_pose)
                                      : c.pose;
}

}  // namespace ringtrack::experiment
