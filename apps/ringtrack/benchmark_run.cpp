#include "benchmark_run.hpp"

#include <algorithm>
#include <chrono>
#include <deque>
#include <map>
#include <set>

#include "ringtrack/pipeline/deskew.hpp"

namespace ringtrack::cli {
namespace {

using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

// Point counts of released scans, by object id (0 = background), until the run ends and the
// objects that ever moved are known.
struct PointTally {
  std::int64_t points = 0;
  std::int64_t removed = 0;
};

}  // namespace

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(values.size() - 1) + 0.5);
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

BenchmarkCase run_benchmark_case(const sim::Scenario& scenario, const core::Config& config,
                                 const BenchmarkCaseOptions& options) {
  BenchmarkCase out;
  out.scenario = scenario.number;
  out.name = scenario.name;
  out.moving = scenario.sensor.motion != sim::SensorMotion::kStatic;

  sim::Simulator simulator(scenario, options.seed);
  pipeline::Pipeline pipeline(config, simulator.model());
  const std::int64_t n = simulator.scan_count();
  out.scans = n;

  std::vector<eval::GroundTruthObject> ground_truth;
  std::vector<eval::TrackObservation> tracks;
  std::set<std::int64_t> ever_moving;
  std::map<std::int64_t, PointTally> tally;
  std::deque<std::vector<std::uint32_t>> pending_labels;  // of the scans in the filter's log

  const auto count_released = [&] {
    for (const mapping::LoggedScan& logged : pipeline.dynamic_filter().released()) {
      const std::vector<std::uint32_t>& labels = pending_labels.front();
      for (std::size_t p = 0; p < logged.cells.size(); ++p) {
        PointTally& t = tally[labels[logged.cells[p]]];
        ++t.points;
        t.removed += logged.removed[p] ? 1 : 0;
      }
      pending_labels.pop_front();
    }
  };

  sim::SimulatedScan scan;
  for (std::int64_t k = 0; k < n; ++k) {
    const auto t0 = Clock::now();
    simulator.next(scan);
    core::Pose pose = scan.pose;
    if (out.moving && options.deskew) {
      const std::int64_t next = simulator.scan_stamp_ns(k + 1);
      pose = pipeline::deskew_scan(scan.scan, scan.pose, simulator.sensor_pose_at(next));
    }
    const auto t1 = Clock::now();
    for (const sim::ObjectTruth& o : scan.objects) {
      if (o.moving) ever_moving.insert(o.id);
      ground_truth.push_back({k, static_cast<std::int64_t>(o.id),
                              std::string(sim::class_name(o.object_class)), o.hit_points,
                              o.centroid_m.cast<double>(), o.body_center_m.cast<double>()});
    }
    pending_labels.push_back(scan.labels);
    const auto t2 = Clock::now();
    const auto& result = pipeline.process(scan.scan, pose);
    const auto t3 = Clock::now();
    if (options.on_scan) options.on_scan(scan, result);
    for (const tracking::Hypothesis& h : result.hypotheses) {
      if (!h.reported) continue;
      tracks.push_back({k, static_cast<std::int64_t>(h.id), h.reported_position, h.dynamic,
                        h.ever_dynamic, h.person});
    }
    out.times.segmentation.push_back(result.times.segmentation_ms);
    out.times.detection.push_back(result.times.detection_ms);
    out.times.tracking.push_back(result.times.tracking_ms);
    out.times.mapping.push_back(result.times.mapping_ms);
    out.times.total.push_back(result.times.total_ms);
    count_released();
    out.simulate_s += seconds(t0, t1);
    out.pipeline_s += seconds(t2, t3);
  }
  const auto t4 = Clock::now();
  pipeline.finish();
  out.pipeline_s += seconds(t4, Clock::now());
  count_released();

  for (const auto& [id, t] : tally) {
    const bool dynamic = id != 0 && ever_moving.count(id) != 0;
    if (dynamic) {
      out.map.dynamic_points += t.points;
      out.map.dynamic_removed += t.removed;
    } else {
      out.map.static_points += t.points;
      out.map.static_kept += t.points - t.removed;
    }
  }
  out.tracking = eval::evaluate_tracks(ground_truth, tracks, options.evaluation);
  if (options.person_figures) {
    eval::TrackingEvalOptions person = options.evaluation;
    person.hypotheses = eval::HypothesisSelection::kPerson;
    out.person = eval::evaluate_tracks(ground_truth, tracks, person);
  }
  return out;
}

}  // namespace ringtrack::cli
