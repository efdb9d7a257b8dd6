// BM_PipelineScan: the whole pipeline on one simulated VLP-16 scan with 10 people walking in an
// open field, in time order with the tracker warmed up (the steady state of a long run).
// BM_PipelineScanMovingPark: the same on the park (trees, bushes, people) seen from the
// benchmark's moving sensor (figure 8, deskewed): the cluttered moving case of the map stage.
// Its second argument turns the recent views' column test (background.moving_column_m) off.

#include <benchmark/benchmark.h>

#include <map>
#include <memory>

#include "ringtrack/pipeline/deskew.hpp"
#include "ringtrack/pipeline/pipeline.hpp"
#include "ringtrack/sim/scenario.hpp"
#include "ringtrack/sim/simulator.hpp"

namespace {

using namespace ringtrack;

constexpr int kScans = 120;
constexpr int kWarmUp = 20;  // scans before timing: tracks exist, the map log is filling
// BM_PipelineScanLongRun: past the map log's delay (50 scans) and the 64 points that settle a
// voxel, so the map has settled as in a long run from a resting sensor.
constexpr int kLongScans = 400;
constexpr int kLongWarmUp = 300;

struct FeedScan {
  sim::SimulatedScan scan;
  core::Pose pose;  // deskewed to the scan's first column for a moving sensor
};

std::vector<FeedScan> simulate(const sim::Scenario& scenario, std::uint64_t seed,
                               int scans = kScans) {
  sim::Simulator simulator(scenario, seed);
  const bool moving = scenario.sensor.motion != sim::SensorMotion::kStatic;
  std::vector<FeedScan> out(static_cast<std::size_t>(scans));
  for (int k = 0; k < scans; ++k) {
    simulator.next(out[k].scan);
    out[k].pose = out[k].scan.pose;
    if (moving) {
      out[k].pose = pipeline::deskew_scan(out[k].scan.scan, out[k].scan.pose,
                                          simulator.sensor_pose_at(simulator.scan_stamp_ns(k + 1)));
    }
  }
  return out;
}

const std::vector<FeedScan>& open_field_scans(int scans = kScans) {
  static std::map<int, std::vector<FeedScan>> data;
  if (!data.contains(scans)) {
    auto scenario = sim::builtin_scenario("1");
    scenario.people = 10;
    data[scans] = simulate(scenario, 7, scans);
  }
  return data.at(scans);
}

const std::vector<FeedScan>& moving_park_scans() {
  static const auto data = [] {
    auto scenario = sim::with_moving_sensor(sim::builtin_scenario("6"));
    return simulate(scenario, 1);
  }();
  return data;
}

void run_pipeline(benchmark::State& state, const std::vector<FeedScan>& data,
                  const core::Config& config = {}, int warm_up = kWarmUp) {
  const auto scans = static_cast<int>(data.size());
  std::unique_ptr<pipeline::Pipeline> pipeline;
  int next = scans;
  std::size_t hypotheses = 0;
  pipeline::StageTimes sum;  // per-stage breakdown, reported as means per scan
  for (auto _ : state) {
    if (next == scans) {  // start over with a fresh pipeline, warmed up outside the timing
      state.PauseTiming();
      pipeline = std::make_unique<pipeline::Pipeline>(config, core::SensorModel::vlp16());
      for (next = 0; next < warm_up; ++next)
        pipeline->process(data[next].scan.scan, data[next].pose);
      state.ResumeTiming();
    }
    const auto& result = pipeline->process(data[next].scan.scan, data[next].pose);
    hypotheses = result.hypotheses.size();
    sum.segmentation_ms += result.times.segmentation_ms;
    sum.detection_ms += result.times.detection_ms;
    sum.tracking_ms += result.times.tracking_ms;
    sum.mapping_ms += result.times.mapping_ms;
    ++next;
  }
  state.counters["hypotheses"] = static_cast<double>(hypotheses);
  const auto mean = [&](double total) {
    return benchmark::Counter(total, benchmark::Counter::kAvgIterations);
  };
  state.counters["segmentation_ms"] = mean(sum.segmentation_ms);
  state.counters["detection_ms"] = mean(sum.detection_ms);
  state.counters["tracking_ms"] = mean(sum.tracking_ms);
  state.counters["mapping_ms"] = mean(sum.mapping_ms);
}

// Argument: mapping.free_space on (1, the default) or off (0).
void BM_PipelineScan(benchmark::State& state) {
  core::Config config;
  config.mapping.free_space = state.range(0) != 0;
  run_pipeline(state, open_field_scans(), config);
}

// The same scans after a long warm-up (kLongWarmUp): what a long run from a resting sensor
// costs per scan once its map has settled, where BM_PipelineScan's young map takes every point.
void BM_PipelineScanLongRun(benchmark::State& state) {
  run_pipeline(state, open_field_scans(kLongScans), core::Config{}, kLongWarmUp);
}

// Argument: mapping.free_space_moving off (0, the default) or on (1), to price the free-space
// line's projections into scans from other viewpoints.
void BM_PipelineScanMovingPark(benchmark::State& state) {
  core::Config config;
  config.mapping.free_space_moving = state.range(0) != 0;
  // The recent views' column test (background.moving_column_m) on or off, side by side.
  if (state.range(1) == 0) config.background.moving_column_m = 0.0;
  run_pipeline(state, moving_park_scans(), config);
}

}  // namespace

BENCHMARK(BM_PipelineScan)
    ->ArgName("free_space")
    ->Arg(1)
    ->Arg(0)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_PipelineScanLongRun)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_PipelineScanMovingPark)
    ->ArgNames({"free_space_moving", "column"})
    ->Args({0, 1})
    ->Args({0, 0})
    ->Args({1, 1})
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
